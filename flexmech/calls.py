"""The public functions: a mechanism from a file or an example's name, and what to ask of it.
Numbers are in the document's units throughout; every problem with a document or an argument is
a flexmech.MechanismError naming the field."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from flexmech.models import Mechanism, MechanismError, compile_mechanism, load_document
from flexmech.service.analyses import ANALYSES, AnalysisRequest
from flexmech.service.examples import document_path
from flexmech.service.export.encoders import c_identifier
from flexmech.service.solvers.equilibrium import EquilibriumResult, solve_equilibrium
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.reports import output_units
from flexmech.service.solvers.sweep import solve_for_target as target_of
from flexmech.service.solvers.sweep import sweep as equilibria_along
from flexmech.views import Report, Solution, Sweep, Table, Target


def load(source: str | Path | Mapping[str, Any], model: str | None = None) -> Mechanism:
    """The compiled mechanism of a document: a file (JSON or YAML), a document as a dict, or the
    name of a shipped example ("gripper"; `flexmech examples` lists them). `model` sets every
    curved beam's (linear, partial_nonlinear, exact; default: as in the document)."""
    document = load_document(dict(source) if isinstance(source, Mapping) else document_path(source))
    return compile_mechanism(document, model)


def keyword(pointer: str) -> str:
    """The keyword naming a numeric field in solve(**values): a load's component by its load's
    name, the field and x or y (/loads/actuation/force/1: actuation_force_y), any other field by
    its whole pointer (/sections/flexure/h: sections_flexure_h)."""
    parts = pointer.strip("/").split("/")
    if parts[0] == "loads":
        parts = parts[1:]
        if len(parts) >= 2 and parts[-1] in ("0", "1"):
            parts[-1] = "xy"[int(parts[-1])]
    return c_identifier("_".join(parts))


def with_values(
    mech: Mechanism, values: Mapping[str, float | str] | None, named: Mapping[str, float | str]
) -> Mechanism:
    """`mech` with fields replaced: `values` by JSON pointer, `named` by keyword()."""
    given = dict(values or {})
    if named:
        fields: dict[str, list[str]] = {}
        for parameter in mech.parameters:
            fields.setdefault(keyword(parameter.pointer), []).append(parameter.pointer)
        for name, value in named.items():
            pointers = fields.get(name)
            if not pointers:
                loads = sorted(k for k, p in fields.items() if p[0].startswith("/loads/"))
                raise MechanismError(f"/{name}", f"no numeric field is named {name} (the loads': {', '.join(loads)})")
            if len(pointers) > 1:
                raise MechanismError(f"/{name}", f"{name} names {' and '.join(pointers)}: give the one by its pointer")
            given[pointers[0]] = value
    return mech.with_values(given) if given else mech


def _solution(result: EquilibriumResult) -> Solution:
    mech = result.mechanism
    outputs = {name: float(v) for name, v in result.outputs().items()} if result.converged else {}
    residual = float(result.residual_norm_force)
    displacements = {name: float(v) for name, v in result.displacements().items()} if result.converged else {}
    return Solution(
        result.status,
        result.iterations,
        residual,
        outputs,
        output_units(mech),
        displacements,
        result,
        mech.document.name,
    )


def solve(
    mech: Mechanism,
    values: Mapping[str, float | str] | None = None,
    /,
    options: NewtonOptions = NewtonOptions(),
    **named: float | str,
) -> Solution:
    """The equilibrium of `mech`, with numeric fields replaced: by JSON pointer in `values`
    ({"/loads/actuation/force/1": 50}) or by keyword (actuation_force_y=50; keyword() says how
    fields are named), numbers in document units or quantities ("50 uN"). Non-convergence is the
    result's status, not an exception."""
    return _solution(solve_equilibrium(with_values(mech, values, named), options))


def solve_for_target(
    mech: Mechanism, input: str, output: str, value: float, options: NewtonOptions = NewtonOptions()
) -> Target:
    """The value of the numeric field `input` (a JSON pointer) at which `output` equals `value`:
    the gripper's closing force is solve_for_target(gripper, "/loads/actuation/force/1",
    "end_effector.x", 0.0).value, in the document's force unit."""
    found = target_of(mech, input, output, float(value), options)
    units = output_units(mech)
    unit = mech.doc_unit(mech.parameter_kind(input))
    return Target(
        found.status,
        input,
        found.value,
        unit,
        output,
        float(value),
        units.get(output, ""),
        _solution(found.equilibrium),
    )


def sweep(
    mech: Mechanism, input: str, values: Sequence[float] | np.ndarray, options: NewtonOptions = NewtonOptions()
) -> Sweep:
    """Equilibria at each of `values` of the numeric field `input` (a JSON pointer, document
    units), each from the last (continuation)."""
    found = equilibria_along(mech, input, np.asarray(values, dtype=float), options)
    unit = mech.doc_unit(mech.parameter_kind(input))
    return Sweep(input, unit, found.values, found.outputs, output_units(mech), found.status, found)


def modes(mech: Mechanism, count: int = 6, at: str = "equilibrium", shapes: bool = True) -> Report:
    """The `count` lowest natural modes about the equilibrium under the document's loads (or
    undeformed): frequencies in Hz, effective masses and shapes (the modes analysis' report)."""
    report = ANALYSES.named("modes").run(
        mech, AnalysisRequest(NewtonOptions(), {"count": count, "at": at, "shapes": shapes})
    )
    mass = report.get("units", {}).get("effective_mass", "")
    rows = [
        (m["mode"], m["kind"], m["frequency"], m["effective_mass"]["x"], m["effective_mass"]["y"])
        for m in report.get("modes", [])
    ]
    heads = ("mode", "kind", "frequency [Hz]", f"effective mass x [{mass}]", f"effective mass y [{mass}]")
    return Report(report, Table(f"{mech.document.name}: modes at {at} ({report['status']})", heads, rows))


def simulate(mech: Mechanism, **simulate: Any) -> Report:
    """A time simulation by the document's `simulate` section, its fields replaced by the keyword
    arguments (until=1.0, step=1e-3, ...): the simulate analysis' report (times, outputs per kept
    state, energies). No time limit: it runs to its end."""
    request = AnalysisRequest(NewtonOptions(time_limit=None), {"simulate": simulate} if simulate else {})
    report = ANALYSES.named("simulate").run(mech, request)
    units = report.get("output_units", {})
    rows = [
        (name, values[-1] if values else None, units.get(name, ""))
        for name, values in report.get("outputs", {}).items()
    ]
    title = f"{mech.document.name}: {report['status']} at t = {report.get('time_reached', 0):g} s"
    return Report(report, Table(title, ("output", "at the end", "unit"), rows))
