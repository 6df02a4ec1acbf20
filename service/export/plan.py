"""What an export holds: the inputs a caller sets, the outputs it reads, the target task and
the iteration limits; every choice checked against the mechanism, problems named by field.

The C names come from the document's names by one mangling (service.export.encoders.c_identifier),
which is not injective: two inputs, outputs or contact outputs that meet in one C name (or in a
macro of the header's own), and a library name that is a file, target or header of the build,
are refused here, naming the fields."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from functools import cache
from importlib.resources import files

from flexmech.models import Mechanism, MechanismError
from flexmech.service.export.encoders import c_identifier

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
class ContactOutput:
    name: str
    c_name: str
    field: str  # the pointer that chose it: /contact_outputs/k, or the document's contact path or pair


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
    contact_outputs: tuple[ContactOutput, ...] = ()  # of the contact task, when the document has contact pairs


MAX_NAME = 40  # characters of the library's name
_OWN_FILES = {
    "main": "main.c, the example's source",
    "bench": "bench.c and the benchmark program bench",
    "check": "check.c and make's target check",
    "example": "the example program",
}
_BUILD_TARGETS = (  # make's and CMake's own targets (CMake refuses a library named as one)
    "all clean install test help preinstall package package_source edit_cache rebuild_cache "
    "list_install_components depend"
).split()
_SYSTEM_LIBRARIES = ("c", "m", "pthread", "dl", "rt")  # linked, or linked implicitly
# <name>.h in a folder on the include path (CMake's target_include_directories) would stand for
# these headers: the C standard's and the POSIX ones the library, its programs and libc include
_SYSTEM_HEADERS = (
    "assert complex ctype errno fenv float inttypes iso646 limits locale math setjmp signal stdalign "
    "stdarg stdatomic stdbool stddef stdint stdio stdlib stdnoreturn string tgmath threads time uchar "
    "wchar wctype pthread sched unistd features alloca endian strings"
).split()
_HELPERS = ("solve", "casadi")  # solve_equilibrium is the driver's own; casadi_* the kernels' helpers


def _reserved(name: str) -> str | None:
    """Why `name` cannot name the library (None: it can)."""
    if name in _OWN_FILES:
        return f"'{name}' names a file of the export's own ({_OWN_FILES[name]})"
    if name in _BUILD_TARGETS:
        return f"'{name}' is a target of make or CMake"
    if name in _SYSTEM_LIBRARIES:
        return f"'{name}' is a system library the build links (lib{name})"
    if name in _SYSTEM_HEADERS:
        return f"{name}.h would stand for the system header <{name}.h> on an include path"
    if name in _HELPERS:
        return f"'{name}' would give functions named as the library's internal ones ({name}_...)"
    return None


def _library_name(mech: Mechanism, given: str) -> str:
    """The library's C name (its functions' and files' prefix): the given name mangled, at most
    MAX_NAME characters; without one, the document's name's (or "mechanism" when that gives no
    usable name: a title in another script, or one of the reserved names)."""
    name = c_identifier(given or mech.document.name or "mechanism")[:MAX_NAME].rstrip("_")
    why = _reserved(name)
    if not given:
        return "mechanism" if why or not re.search("[0-9A-Za-z]", mech.document.name) else name
    if not re.search("[0-9A-Za-z]", given):
        raise MechanismError(
            "/name", f"'{given}' has no ASCII letter or digit to make the library's C name of: give one that has"
        )
    if why:
        raise MechanismError("/name", f"{why}: choose another name for the library")
    return name


@cache
def _header_suffixes() -> frozenset[str]:
    """The header's own macros after <NAME>_ (OK, OUT_OF_RANGE, N_INPUTS, ...), read from its template."""
    text = (files("flexmech.service.export") / "templates" / "header.h.in").read_text()
    return frozenset(re.findall(r"#define @UPPER@_(\w+)", text))


def _distinct(items: list[tuple[str, str, str]], macro: str) -> None:
    """items: (field, name, C name) of one namespace (inputs, outputs or contact outputs), whose
    header macros are <NAME>_<macro>_<C NAME>. Two that meet in one C name, or one whose macro
    is one of the header's own, are a MechanismError naming both fields."""
    own = _header_suffixes()
    seen: dict[str, tuple[str, str]] = {}
    for where, name, c_name in items:
        suffix = f"{macro}_{c_name.upper()}"
        if suffix in own:
            raise MechanismError(
                where, f"'{name}' becomes the macro <NAME>_{suffix}, one of the header's own: rename it"
            )
        if c_name in seen:
            first_where, first = seen[c_name]
            problem = f"'{name}' and '{first}'{_at(first_where, first)} both become the C name {c_name}: rename one"
            other = f"'{first}' and '{name}'{_at(where, name)} both become the C name {c_name}: rename one"
            raise MechanismError(where, problem, ((where, problem), (first_where, other)))
        seen[c_name] = (where, name)


def _at(where: str, name: str) -> str:
    return "" if where == name else f" ({where})"


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


def _outputs(mech: Mechanism, chosen: tuple[str, ...]) -> list[tuple[str, Output]]:
    """(field, output) of the chosen outputs: field /outputs/k of the given ones; of the default
    ones (the document's named outputs, else the free body coordinates, else, every body held
    or moved by the document, their reactions: the forces its motion takes), the document's
    output or body they belong to."""
    names = mech.graphs.output_names
    if not chosen:
        own = [n for n in names if not n.startswith(("bodies.", "reactions.", "elements.")) and n != "energy"]
        if own:  # an output's name has no '.': the part before the first one is its name
            return [(f"/outputs/{n.split('.')[0]}", _output(mech, n)) for n in own]
        bodies = mech.structure.bodies
        free = [
            (f"/bodies/{bodies[b]}", _output(mech, _as_output(names, mech.structure.coordinate_name(b, c))))
            for b, c in mech.structure.free
        ]
        held = [(f"/bodies/{n.split('.')[1]}", _output(mech, n)) for n in names if n.startswith("reactions.")]
        return free or held  # without outputs, C has no zero-length arrays: one of them is never empty
    out = []
    for k, name in enumerate(chosen):
        if name not in names:
            raise MechanismError(f"/outputs/{k}", f"unknown output '{name}' (outputs: {', '.join(names[:12])}, ...)")
        out.append((f"/outputs/{k}", _output(mech, name)))
    return out


def _as_output(names: tuple[str, ...], coordinate: str) -> str:
    return coordinate if coordinate in names else f"bodies.{coordinate}"


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


def contact_outputs(mech: Mechanism, options: ExportOptions) -> tuple[ContactOutput, ...]:
    """The contact task's outputs: the given ones, else the document's contact path outputs,
    else every pair's results (service.contact.outputs.PAIR_OUTPUTS) and any output of the
    structure's named "contacts." (as the contact problem names them); none without pairs or
    with contact "no"."""
    from flexmech.service.contact.outputs import PAIR_OUTPUTS

    structure = mech.structure.contacts
    if options.contact == "no" or structure is None or not structure.pairs:
        return ()
    path = mech.document.contacts.path
    if options.contact_outputs:
        chosen = [(f"/contact_outputs/{k}", n) for k, n in enumerate(options.contact_outputs)]
    elif path is not None and path.outputs:
        chosen = [(f"/contacts/path/outputs/{k}", n) for k, n in enumerate(path.outputs)]
    else:
        chosen = [
            (f"/contacts/pairs/{p.name}", f"contacts.{p.name}.{q}") for p in structure.pairs for q, _ in PAIR_OUTPUTS
        ]
        pairs = {n for _, n in chosen}  # a structure may name a pair's result too (gripper_grasp_dynamics)
        chosen += [
            ("/outputs/contacts", n) for n in mech.graphs.output_names if n.startswith("contacts.") and n not in pairs
        ]
    return tuple(ContactOutput(n, c_identifier(n.removeprefix("contacts.")), where) for where, n in chosen)


def export_plan(mech: Mechanism, model: str, options: ExportOptions) -> ExportPlan:
    """The plan of an export of `mech` (compiled with `model`), or MechanismError naming the field."""
    name = _library_name(mech, options.name)
    given = bool(options.inputs)
    pointers = list(options.inputs) or _default_inputs(mech)
    unknown = [p for p in options.ranges if p not in pointers]
    if unknown:
        raise MechanismError(f"/ranges/{unknown[0]}", "a range for a field that is not an exported input")
    inputs = [_input(mech, p, f"/inputs/{k}", options.ranges.get(p)) for k, p in enumerate(pointers)]
    _distinct([(f"/inputs/{k}" if given else i.pointer, i.pointer, i.c_name) for k, i in enumerate(inputs)], "IN")
    placed = _outputs(mech, options.outputs)
    _distinct([(where, o.name, o.c_name) for where, o in placed], "OUT")
    outputs = [o for _, o in placed]
    contact = contact_outputs(mech, options)
    _distinct([(c.field, c.name, c.c_name) for c in contact], "CONTACT")
    target = _target(mech, options, inputs, outputs)
    return ExportPlan(name, model, tuple(inputs), tuple(outputs), target, options, contact)
