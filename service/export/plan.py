"""What an export holds: the inputs a caller sets, the outputs it reads, the target task and
the iteration limits; every choice checked against the mechanism, problems named by field."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from models import Mechanism, MechanismError

_DEFAULT_RANGES = {  # a field's own check (models.graph.collector) as (low, high, low excluded)
    "positive": (0.0, math.inf, True),
    "nonnegative": (0.0, math.inf, False),
    "arc_angle": (0.0, 2 * math.pi, True),
    "poisson": (-1.0, 0.5, True),
}


@dataclass(frozen=True)
class ExportOptions:
    """What to export. inputs: numeric fields (JSON pointers; default: every load and prescribed
    motion); outputs: output names (default: the document's named outputs, else the free body
    coordinates); ranges: per input pointer (low, high) in document units; target: (output,
    value, input pointer) for the target task (default: the document's sweep `until`)."""

    name: str = ""
    inputs: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    ranges: dict[str, tuple[float, float]] = field(default_factory=dict)
    target: tuple[str, float, str] | None = None
    contact: str = "auto"  # auto | yes | no: the contact state task (service.export.kernels._contact)
    contact_outputs: tuple[str, ...] = ()  # the contact task's (default: the document's contact path outputs)
    max_iterations: int = 30
    tolerance: float = 1e-12  # nondimensional |R|_inf
    line_search_halvings: int = 6

    def __post_init__(self):
        if not 1 <= self.max_iterations <= 1000:
            raise MechanismError("/max_iterations", f"must lie in 1..1000, got {self.max_iterations}")
        if not 0 < self.tolerance < 1e-3:
            raise MechanismError("/tolerance", f"must lie in (0, 1e-3), got {self.tolerance:g}")
        if self.contact not in ("auto", "yes", "no"):
            raise MechanismError("/contact", f"unknown choice '{self.contact}' (auto, yes, no)")
        if not 0 <= self.line_search_halvings <= 30:
            raise MechanismError("/line_search_halvings", f"must lie in 0..30, got {self.line_search_halvings}")


@dataclass(frozen=True)
class Input:
    pointer: str
    c_name: str
    unit: str
    kind: str
    slot: int  # index in the parameter vector p
    nd_per_unit: float  # p[slot] = value * nd_per_unit
    low: float  # document units
    high: float
    low_excluded: bool
    default: float  # the document's value


@dataclass(frozen=True)
class Output:
    name: str
    c_name: str
    unit: str
    index: int  # in the mechanism's outputs
    unit_per_nd: float  # value = y_nd * unit_per_nd


@dataclass(frozen=True)
class Target:
    output: Output
    input: int  # index into the plan's inputs: the input the target task solves for
    default_goal: float


@dataclass(frozen=True)
class ExportPlan:
    name: str
    model: str
    inputs: tuple[Input, ...]
    outputs: tuple[Output, ...]
    target: Target | None
    options: ExportOptions


def c_identifier(text: str) -> str:
    """A C identifier from a name or pointer: letters, digits and underscores, lower case."""
    out = re.sub(r"[^0-9a-zA-Z]+", "_", text).strip("_").lower()
    return out if out and not out[0].isdigit() else f"x_{out}"


_POSE = re.compile(r"^/contacts/objects/[^/]+/(centre/[01]|angle)$")


def _default_inputs(mech: Mechanism) -> list[str]:
    """Every load and prescribed motion, and the contact objects' poses."""
    moving = [p.pointer for p in mech.parameters if p.pointer.startswith("/loads/") or _POSE.match(p.pointer)]
    if not moving:
        raise MechanismError("/loads", "the document has no loads, prescribed motions or objects to export as inputs")
    return moving


def _input_name(pointer: str) -> str:
    parts = pointer.strip("/").split("/")[1:]  # without the section: actuation/force/1
    if parts and parts[0] == "objects":
        parts = parts[1:]  # a contact object's pose: ellipse/centre/0
    if len(parts) >= 2 and parts[-1] in ("0", "1"):
        parts[-1] = "xy"[int(parts[-1])]
    return c_identifier("_".join(parts))


def _input(mech: Mechanism, pointer: str, where: str, given: tuple[float, float] | None) -> Input:
    try:
        k = mech.parameter_index(pointer)
    except MechanismError as exc:
        raise MechanismError(where, f"'{pointer}' is {exc.problem}") from None
    param = mech.parameters[k]
    per_unit = mech.nd_per_doc(param.kind)
    si_per_unit = mech.doc_factor(param.kind)
    low, high, excluded = _DEFAULT_RANGES.get(param.check or "", (-math.inf, math.inf, False))
    low, high = low / si_per_unit, high / si_per_unit
    if given is not None:
        g_low, g_high = float(given[0]), float(given[1])
        if not (math.isfinite(g_low) and math.isfinite(g_high) and g_low < g_high):
            raise MechanismError(f"/ranges/{pointer}", f"expected low < high, both finite, got {given}")
        low, high, excluded = max(low, g_low), min(high, g_high), excluded and g_low <= low
    name = _input_name(pointer) if pointer.startswith(("/loads/", "/contacts/objects/")) else c_identifier(pointer)
    return Input(
        pointer, name, mech.doc_unit(param.kind), param.kind, k, per_unit, low, high, excluded, mech.value(pointer)
    )


def _outputs(mech: Mechanism, chosen: tuple[str, ...]) -> list[Output]:
    names = mech.graphs.output_names
    if not chosen:
        own = tuple(n for n in names if not n.startswith(("bodies.", "reactions.", "elements.")) and n != "energy")
        chosen = own or tuple(mech.structure.coordinate_name(b, c).replace("/", ".") for b, c in mech.structure.free)
        chosen = tuple(n if n in names else f"bodies.{n}" for n in chosen)
    out = []
    for k, name in enumerate(chosen):
        if name not in names:
            raise MechanismError(f"/outputs/{k}", f"unknown output '{name}' (outputs: {', '.join(names[:12])}, ...)")
        out.append(_output(mech, name))
    return out


def _output(mech: Mechanism, name: str) -> Output:
    j = mech.graphs.output_names.index(name)
    kind = mech.graphs.output_kinds[j]
    return Output(name, c_identifier(name), mech.doc_unit(kind), j, 1.0 / mech.nd_per_doc(kind))


def _target(mech: Mechanism, options: ExportOptions, inputs: list[Input], outputs: list[Output]) -> Target | None:
    spec = options.target
    if spec is None and mech.document.sweep is not None and mech.document.sweep.until is not None:
        until = mech.document.sweep.until
        spec = (until.output, float(until.equals), mech.document.sweep.path)
    if spec is None:
        return None
    output, goal, pointer = spec
    by = [i for i, item in enumerate(inputs) if item.pointer == pointer]
    if not by:
        raise MechanismError("/target/input", f"'{pointer}' is not one of the exported inputs")
    names = mech.graphs.output_names
    if output not in names:
        raise MechanismError("/target/output", f"unknown output '{output}'")
    return Target(_output(mech, output), by[0], goal)


def export_plan(mech: Mechanism, model: str, options: ExportOptions) -> ExportPlan:
    """The plan of an export of `mech` (compiled with `model`), or MechanismError naming the field."""
    pointers = list(options.inputs) or _default_inputs(mech)
    unknown = [p for p in options.ranges if p not in pointers]
    if unknown:
        raise MechanismError(f"/ranges/{unknown[0]}", "a range for a field that is not an exported input")
    inputs = [_input(mech, p, f"/inputs/{k}", options.ranges.get(p)) for k, p in enumerate(pointers)]
    outputs = _outputs(mech, options.outputs)
    for group in (inputs, outputs):
        seen: set[str] = set()
        for item in group:
            if item.c_name in seen:
                raise MechanismError("/inputs" if group is inputs else "/outputs", f"'{item.c_name}' is named twice")
            seen.add(item.c_name)
    name = c_identifier(options.name or mech.document.name or "mechanism")[:40]
    return ExportPlan(name, model, tuple(inputs), tuple(outputs), _target(mech, options, inputs, outputs), options)
