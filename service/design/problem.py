"""A design problem checked against its mechanism: which parameters move, which outputs are
the objective and constraints, in which load cases, and their units and scales.

Outputs are the names /v1/solve reports (reactions.tip.Fy, end_effector.x,
elements.L1.stress_max, energy, ...), plus
  stiffness.<body>.<x|y|angle>   the diagonal of the condensed tangent stiffness K_T
  frequency.<k>                  the k-th natural frequency (Hz) about the case's equilibrium
  response(<output>, <load's component>, <Hz>)   the amplitude of the output under a harmonic
                                 load of unit amplitude at that frequency (output unit per load unit;
                                 the spec's `damping`)
  /a/numeric/field               the value of a numeric field of the case (e.g. a length)
Every problem names its field under `pointer` (e.g. /optimize/design/0/lower).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.documents.optimize_spec import OptimizeSpec
from flexmech.models.graph.structure import COORDINATES
from flexmech.service.contact.outputs import PAIR_OUTPUTS
from flexmech.service.design.robust import Robustness, robustness

STIFFNESS_PREFIX = "stiffness."
FREQUENCY_PREFIX = "frequency."
RESPONSE = re.compile(r"response\(([^,]+),([^,]+),([^,)]+)\)")
_STIFFNESS_KINDS = {"x": "stiffness", "y": "stiffness", "angle": "moment"}  # per unit length / per rad


@dataclass(frozen=True)
class OutputRef:
    """One output of one case: from the outputs graph, a stiffness, or a parameter."""

    name: str
    case: int
    source: str  # output | stiffness | parameter | frequency | response
    index: int  # into the outputs, the free coordinates or the parameters; the mode (0-based)
    kind: str
    input: int = -1  # a response's load parameter
    frequency: float = 0.0  # a response's frequency (Hz)
    unit: str = ""  # a response's unit (its value is in it: no kind converts it)
    sigmas: float = 0.0  # robust: mean + sigmas * sigma (signed), first order (service.design.robust)
    robust: Robustness | None = None  # the scatter (and, for the yield, the specs) it needs


@dataclass(frozen=True)
class Bounded:
    output: OutputRef
    lower: float  # document units, -inf / inf when absent
    upper: float
    pointer: str


@dataclass(frozen=True)
class DesignProblem:
    mechanism: Mechanism
    spec: OptimizeSpec
    paths: tuple[str, ...]
    slots: tuple[int, ...]  # parameter index of each design variable
    nd_per_doc: np.ndarray  # per design variable
    start: np.ndarray  # document units (the document's values)
    lower: np.ndarray  # document units, -inf / inf when absent
    upper: np.ndarray
    scale: np.ndarray  # document units
    case_names: tuple[str, ...]
    case_p: tuple[np.ndarray, ...]  # nondimensional parameters of each case (design slots: start values)
    objective: OutputRef
    sign: float  # +1 minimize, -1 maximize
    constraints: tuple[Bounded, ...]

    def output_factor(self, ref: OutputRef) -> float:
        """Nondimensional value of one document unit of the output."""
        return 1.0 if ref.source == "response" else self.mechanism.nd_per_doc(ref.kind)


def design_problem(mech: Mechanism, spec: OptimizeSpec, pointer: str = "/optimize") -> DesignProblem:
    paths, slots, factors, lower, upper, scale, start = [], [], [], [], [], [], []
    for k, var in enumerate(spec.design):
        here = f"{pointer}/design/{k}"
        try:
            slot = mech.parameter_index(var.path)
        except MechanismError as exc:
            raise MechanismError(f"{here}/path", f"'{var.path}' is {exc.problem}") from None
        if var.path in paths:
            raise MechanismError(f"{here}/path", f"'{var.path}' is already a design variable")
        for bound in ("lower", "upper", "scale"):  # the field's own checks (a positive h, an arc angle)
            if getattr(var, bound) is not None:
                mech.checked_si(var.path, getattr(var, bound), f"{here}/{bound}", own_checks=bound != "scale")
        lo = -np.inf if var.lower is None else float(var.lower)
        hi = np.inf if var.upper is None else float(var.upper)
        if lo > hi:
            raise MechanismError(f"{here}/lower", f"lower bound {var.lower:g} is above the upper bound {var.upper:g}")
        value = mech.value(var.path)
        paths.append(var.path)
        slots.append(slot)
        factors.append(mech.nd_per_doc(mech.parameters[slot].kind))
        lower.append(lo)
        upper.append(hi)
        scale.append(var.scale if var.scale is not None else _typical(value, lo, hi))
        start.append(value)

    case_names, case_p = _cases(mech, spec, pointer, set(paths))
    here = f"{pointer}/objective"
    objective = _output(mech, spec.objective.output, spec.objective.case, case_names, here)
    sign = 1.0 if spec.objective.sense == "minimize" else -1.0
    objective = _robust(mech, objective, sign * (spec.objective.sigmas or 0.0), here)
    constraints = _constraints(mech, spec, case_names, pointer)
    _robust_without_contact(objective, here, constraints)
    return DesignProblem(
        mech,
        spec,
        tuple(paths),
        tuple(slots),
        np.array(factors),
        np.array(start),
        np.array(lower),
        np.array(upper),
        np.array(scale, dtype=float),
        case_names,
        case_p,
        objective,
        sign,
        tuple(constraints),
    )


def _constraints(mech: Mechanism, spec: OptimizeSpec, case_names: tuple[str, ...], pointer: str) -> list[Bounded]:
    """The bounded outputs: a robust one (sigmas) bounds mean + k sigma above and mean - k sigma
    below, a row each; a yield's bounds are on its logarithm, which the NLP holds."""
    constraints: list[Bounded] = []
    for k, con in enumerate(spec.constraints):
        here = f"{pointer}/constraints/{k}"
        ref = _output(mech, con.output, con.case, case_names, here)
        lo = con.equals if con.equals is not None else con.lower
        hi = con.equals if con.equals is not None else con.upper
        lo = -np.inf if lo is None else float(lo)
        hi = np.inf if hi is None else float(hi)
        if lo > hi:
            raise MechanismError(f"{here}/lower", f"lower bound {lo:g} is above the upper bound {hi:g}")
        if ref.source == "yield":  # the NLP bounds its logarithm (service.design.robust)
            constraints.append(Bounded(ref, *(np.log(b) if b > 0 else -np.inf for b in (lo, hi)), here))
            continue
        if not con.sigmas:
            constraints.append(Bounded(ref, lo, hi, here))
            continue
        if con.equals is not None:
            raise MechanismError(f"{here}/sigmas", "a scattered output cannot equal a value: give lower and/or upper")
        for bound, k_sign in ((hi, 1.0), (lo, -1.0)):  # mean + k sigma <= upper, mean - k sigma >= lower
            if np.isfinite(bound):
                one = _robust(mech, ref, k_sign * con.sigmas, here)
                constraints.append(
                    Bounded(one, bound if k_sign < 0 else -np.inf, bound if k_sign > 0 else np.inf, here)
                )
    return constraints


def _robust(mech: Mechanism, ref: OutputRef, sigmas: float, here: str) -> OutputRef:
    """The output as mean + sigmas * sigma (first order) when sigmas is not zero."""
    if not sigmas:
        return ref
    if ref.source != "output":
        raise MechanismError(f"{here}/sigmas", f"mean + k sigma is given for the solve's outputs, not for '{ref.name}'")
    return replace(ref, sigmas=sigmas, robust=robustness(mech, f"{here}/sigmas"))


def _robust_without_contact(objective: OutputRef, here: str, constraints: list[Bounded]) -> None:
    """A problem over contact states (service.contact.design) has no first-order blocks: refuse
    a robust output there rather than optimize its nominal value."""
    named = [(objective, here), *((c.output, c.pointer) for c in constraints)]
    if not any(ref.source == "contact" for ref, _ in named):
        return
    for ref, where in named:
        if ref.robust is not None:
            field = "output" if ref.source == "yield" else "sigmas"
            raise MechanismError(
                f"{where}/{field}", "robust design (sigmas, yield) is not available in a problem on contact results"
            )


def _typical(value: float, lo: float, hi: float) -> float:
    """A design variable's size for scaling: its start value, else its bounds' span, else 1."""
    if value != 0:
        return abs(value)
    if np.isfinite(lo) and np.isfinite(hi) and hi > lo:
        return hi - lo
    return 1.0


def _cases(mech: Mechanism, spec: OptimizeSpec, pointer: str, design: set[str]):
    if not spec.cases:
        return ("nominal",), (mech.p(),)
    names, ps = [], []
    for name, case in spec.cases.items():
        mech_case = mech
        for path, value in case.overrides.items():
            here = f"{pointer}/cases/{name}/overrides/{path.replace('~', '~0').replace('/', '~1')}"
            if path in design:
                raise MechanismError(here, f"'{path}' is a design variable: a case cannot fix it")
            try:
                mech_case = mech_case.with_values({path: value})
            except MechanismError as exc:
                raise MechanismError(here, exc.problem) from None
        names.append(name)
        ps.append(mech_case.p())
    return tuple(names), tuple(ps)


def output_names(mech: Mechanism) -> list[str]:
    """Every output an objective or constraint may name (besides numeric-field paths)."""
    stiffness = [f"{STIFFNESS_PREFIX}{name}" for name in mech.free_coordinates]
    return list(mech.graphs.output_names) + stiffness + [f"{FREQUENCY_PREFIX}<k>"]


def _output(mech: Mechanism, name: str, case: str | None, case_names: tuple[str, ...], here: str) -> OutputRef:
    if case is None:
        if len(case_names) > 1:
            raise MechanismError(f"{here}/case", f"name the load case ({', '.join(case_names)})")
        c = 0
    elif case not in case_names:
        raise MechanismError(f"{here}/case", f"unknown load case '{case}' (cases: {', '.join(case_names)})")
    else:
        c = case_names.index(case)
    g = mech.graphs
    if name in g.output_names:
        k = g.output_names.index(name)
        return OutputRef(name, c, "output", k, g.output_kinds[k])
    if name.startswith(STIFFNESS_PREFIX) and name[len(STIFFNESS_PREFIX) :] in mech.free_coordinates:
        k = mech.free_coordinates.index(name[len(STIFFNESS_PREFIX) :])
        coordinate = COORDINATES[mech.structure.free[k][1]]
        return OutputRef(name, c, "stiffness", k, _STIFFNESS_KINDS[coordinate])
    response = RESPONSE.fullmatch(name.replace(" ", ""))
    if response is not None:
        return _response(mech, name, c, here, *response.groups())
    if name.startswith(FREQUENCY_PREFIX):
        mode = name[len(FREQUENCY_PREFIX) :]
        if not mode.isdigit() or int(mode) < 1:
            raise MechanismError(f"{here}/output", f"'{name}': name a mode by its number from 1 (frequency.1)")
        return OutputRef(name, c, "frequency", int(mode) - 1, "frequency")
    if name.startswith("contacts.") and mech.structure.contacts is not None:
        kinds = dict(PAIR_OUTPUTS)
        pair, _, quantity = name[len("contacts.") :].rpartition(".")
        if pair in [p.name for p in mech.structure.contacts.pairs] and quantity in kinds:
            return OutputRef(name, c, "contact", 0, kinds[quantity])
    if name == "yield":
        return OutputRef(
            name, c, "yield", 0, "dimensionless", robust=robustness(mech, f"{here}/output", with_specs=True)
        )
    if name.startswith("/"):
        try:
            k = mech.parameter_index(name)
        except MechanismError as exc:
            raise MechanismError(f"{here}/output", f"'{name}' is {exc.problem}") from None
        return OutputRef(name, c, "parameter", k, mech.parameters[k].kind)
    close = [n for n in output_names(mech) if n.split(".")[0] == name.split(".")[0]][:8]
    hint = f" (outputs like it: {', '.join(close)})" if close else " (see the outputs /v1/solve reports)"
    raise MechanismError(f"{here}/output", f"unknown output '{name}'{hint}")


def _response(mech: Mechanism, name: str, c: int, here: str, output: str, load: str, hertz: str) -> OutputRef:
    """response(<output>, <load's component>, <Hz>): checked, its unit output unit per load unit."""
    g = mech.graphs
    if output not in g.output_names:
        raise MechanismError(f"{here}/output", f"'{name}': no output '{output}'")
    try:
        k = mech.parameter_index(load)
        frequency = float(hertz)
    except MechanismError as exc:
        raise MechanismError(f"{here}/output", f"'{name}': {load} is {exc.problem}") from None
    except ValueError:
        raise MechanismError(f"{here}/output", f"'{name}': the frequency '{hertz}' is not a number (Hz)") from None
    if mech.parameters[k].kind not in ("force", "moment") or not frequency > 0:
        raise MechanismError(
            f"{here}/output", f"'{name}': name a load's force or moment component and a frequency > 0 Hz"
        )
    index = g.output_names.index(output)
    kind = g.output_kinds[index]
    unit = f"{mech.doc_unit(kind)}/{mech.doc_unit(mech.parameters[k].kind)}"
    return OutputRef(name, c, "response", index, kind, k, frequency, unit)
