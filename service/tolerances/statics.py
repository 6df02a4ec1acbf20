"""The responses of a statics tolerance analysis: outputs at the equilibrium under the
document's loads, and the value of a target's field (the actuation force that closes a
gripper), each sample solved by Newton from the nominal state (the target's field joining the
unknowns as in service.solvers.sweep.solve_for_target). First order from the exact
sensitivities (service.design.sensitivity)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.documents.tolerances import ToleranceTarget
from flexmech.models.units import quantity_to_si
from flexmech.service.design.sensitivity import equilibrium_sensitivities
from flexmech.service.solvers.equilibrium import newton, solve_equilibrium
from flexmech.service.solvers.newton import NewtonOptions, iterate_dense
from flexmech.service.solvers.sweep import solve_for_target, target_function
from flexmech.service.tolerances.fields import Scatter
from flexmech.service.tolerances.responses import Responses


def default_outputs(mech: Mechanism) -> list[str]:
    """The document's named outputs, every component (end_effector.x, anchor.Fy, ...)."""
    named = tuple(f"{name}." for name in mech.document.outputs)
    return [name for name in mech.graphs.output_names if name.startswith(named)]


@dataclass
class _Target:
    path: str
    slot: int
    output: int
    goal: float  # nondimensional
    x0: np.ndarray  # [z; the field] of the nominal solution, nondimensional


def statics_responses(
    mech: Mechanism, scatter: Scatter, outputs: list[str] | None, target: ToleranceTarget | None, options: NewtonOptions
) -> Responses:
    """Outputs under the document's loads (and the target's field) at the nominal design, their
    first-order derivatives by the toleranced fields, and how to evaluate a sample."""
    names = default_outputs(mech) if outputs is None else outputs
    known = mech.graphs.output_names
    for k, name in enumerate(names):
        if name not in known:
            raise MechanismError(
                f"/outputs/{k}", f"unknown output '{name}' (outputs: {', '.join(default_outputs(mech))})"
            )
    nominal_state = solve_equilibrium(mech, options)
    if not nominal_state.converged:
        raise MechanismError("/document", f"the nominal design does not solve: {nominal_state.status}")
    rows = [known.index(name) for name in names]
    p0 = mech.p()
    y0 = np.asarray(mech.graphs.outputs(nominal_state.z, p0)).ravel()
    out_kinds = [mech.graphs.output_kinds[r] for r in rows]
    nominal = [y0[r] / mech.nd_per_doc(kind) for r, kind in zip(rows, out_kinds)]
    jacobian = equilibrium_sensitivities(mech, nominal_state.z, scatter.paths, names).matrix if names else None
    kinds, found = list(out_kinds), None
    if target is not None:
        found, row, kind = _nominal_target(mech, scatter, target, options)
        names = [*names, target.path]
        nominal.append(mech.value(target.path) if found is None else found[1])
        kinds.append(kind)
        jacobian = row if jacobian is None else np.vstack([jacobian, row])
    solve_target = _target_solver(mech, target, found[0], options) if found is not None else None

    def evaluate(deviations: np.ndarray, stop: Callable[[], bool]) -> tuple[np.ndarray, list[str]]:
        return _samples(mech, scatter, rows, out_kinds, nominal_state.z, solve_target, deviations, options, stop)

    units = [mech.doc_unit(kind) for kind in kinds]
    return Responses(names, kinds, units, np.array(nominal), np.atleast_2d(jacobian), evaluate)


def _nominal_target(mech: Mechanism, scatter: Scatter, target: ToleranceTarget, options: NewtonOptions):
    """((the target's data, its value in document units), its sensitivity row, its kind)."""
    try:
        slot = mech.parameter_index(target.path)
    except MechanismError as exc:
        raise MechanismError("/tolerances/target/path", exc.problem) from None
    names = mech.graphs.output_names
    if target.output not in names:
        raise MechanismError("/tolerances/target/output", f"unknown output '{target.output}'")
    if slot in scatter.slots:
        raise MechanismError("/tolerances/target/path", f"'{target.path}' is toleranced: the target solves for it")
    m = names.index(target.output)
    out_kind = mech.graphs.output_kinds[m]
    goal = _output_goal(mech, target, out_kind)
    found = solve_for_target(mech, target.path, target.output, goal, options)
    if found.status != "converged":
        raise MechanismError("/tolerances/target", f"the nominal design does not reach the target: {found.status}")
    solved = found.equilibrium
    row = equilibrium_sensitivities(
        solved.mechanism, solved.z, scatter.paths, [target.path], (target.path, target.output)
    ).matrix
    x0 = np.concatenate([solved.z, [solved.mechanism.p()[slot]]])
    kind = mech.parameters[slot].kind
    return (_Target(target.path, slot, m, goal * mech.nd_per_doc(out_kind), x0), found.value), row, kind


def _output_goal(mech: Mechanism, target: ToleranceTarget, out_kind: str) -> float:
    """The target's value of its output, document units."""
    si = quantity_to_si(target.equals, out_kind, mech.doc_unit(out_kind), "/tolerances/target/equals")
    return si / mech.doc_factor(out_kind)


def _target_solver(mech: Mechanism, target: ToleranceTarget, data: _Target, options: NewtonOptions):
    """p -> (status, the target field's value in document units) by Newton from the nominal solution."""
    f = target_function(mech.graphs, data.slot, data.output, mech.n_free, len(mech.parameters))
    full = replace(options, jacobian="full")
    factor = mech.nd_per_doc(mech.parameters[data.slot].kind)

    def solve(p: np.ndarray) -> tuple[str, float]:
        def evaluate(x):
            G, J = f(x, p, data.goal)
            return np.asarray(G).ravel(), np.asarray(J)

        status, x, *_ = iterate_dense(evaluate, data.x0, full)
        return status, float(x[-1] / factor)

    return solve


def _samples(mech, scatter, rows, out_kinds, z0, solve_target, deviations, options, stop):
    """(samples x responses) in document units, NaN where a sample did not solve; statuses."""
    p0, slots = mech.p(), scatter.slots
    nd = scatter.nondimensional(mech, deviations)
    scale = np.array([mech.nd_per_doc(kind) for kind in out_kinds])
    width = len(rows) + (solve_target is not None)
    values, statuses = np.full((len(nd), width), np.nan), []
    for i, move in enumerate(nd):
        if stop():
            break
        p = p0.copy()
        p[slots] += move
        state = newton(mech, p, z0, options)
        status = state.status
        if state.converged:
            values[i, : len(rows)] = np.asarray(mech.graphs.outputs(state.z, p)).ravel()[rows] / scale
        if solve_target is not None:
            reached, value = solve_target(p)
            values[i, -1] = value if reached == "converged" else np.nan
            status = status if reached == "converged" else f"target {reached}"
        statuses.append(status)
    return values, statuses
