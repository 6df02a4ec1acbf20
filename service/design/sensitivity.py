"""Exact sensitivities by the implicit function theorem.

At an equilibrium R(z, p) = 0:  dz/dp = -K^-1 dR/dp,  dy/dp = dy/dz dz/dp + dy/dp|_z.
With a target (the value of one numeric field t that makes an output equal a value, e.g.
the actuation force that closes a gripper), t joins the unknowns and the target equation
joins R. At an optimum, the KKT conditions of the design NLP on its active set play the
role of R (multipliers below the activity tolerance, or constraints off their bounds, are
left out: a strictly inactive inequality has no say in the local solution).
All derivatives are in document units: output unit per parameter unit.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.graph.assembly import graphs_for
from flexmech.models.graph.structure import Structure
from flexmech.service.design.optimize import ACTIVE_TOLERANCE, Prepared, StartResult
from flexmech.service.design.sensitivity_table import Sensitivities  # noqa: F401 (re-exported)


@lru_cache(maxsize=16)
def _derivatives(structure: Structure) -> ca.Function:
    """(z, p) -> (K, dR/dp, dy/dz, dy/dp) of a structure, built once."""
    g = graphs_for(structure)
    z = ca.SX.sym("z", structure.n_unknowns)
    p = ca.SX.sym("p", len(structure.parameters))
    R = g.residual(z, p)
    y = g.outputs(z, p)
    return ca.Function(
        "sensitivity_terms",
        [z, p],
        [ca.jacobian(R, z), ca.jacobian(R, p), ca.jacobian(y, z), ca.jacobian(y, p)],
        ["z", "p"],
        ["K", "R_p", "y_z", "y_p"],
        dict(cse=True),
    )


def _rows(mech: Mechanism, outputs: list[str], pointer: str) -> list[int]:
    names = mech.graphs.output_names
    rows = []
    for k, name in enumerate(outputs):
        if name not in names:
            raise MechanismError(f"{pointer}/{k}", f"unknown output '{name}'")
        rows.append(names.index(name))
    return rows


def equilibrium_sensitivities(
    mech: Mechanism, z: np.ndarray, parameters: list[str], outputs: list[str], target: tuple[str, str] | None = None
) -> Sensitivities:
    """d(outputs)/d(parameters) at the equilibrium z of `mech` (nondimensional state).

    target = (path, output): the field `path` is not held but follows the parameters so that
    `output` keeps its value (mech must hold the target's solution); `path` may then be named
    among the outputs, e.g. the closing force."""
    slots = mech.parameter_indices(parameters, "/parameters")
    names = list(mech.graphs.output_names)
    wanted = [o for o in outputs if not (target is not None and o == target[0])]
    rows = _rows(mech, wanted, "/outputs")
    p = mech.p()
    K, R_p, y_z, y_p = (np.asarray(a) for a in _derivatives(mech.structure.unnamed)(z, p))
    n = K.shape[0]
    if target is None:
        A, B = K, R_p[:, slots]
    else:
        t = mech.parameter_indices([target[0]], "/target/path")[0]
        o = _rows(mech, [target[1]], "/target/output")[0]
        A = np.block([[K, R_p[:, [t]]], [y_z[[o], :], y_p[[o], [t]].reshape(1, 1)]])
        B = np.vstack([R_p[:, slots], y_p[[o], :][:, slots]])
    try:
        dw = -np.linalg.solve(A, B)
    except np.linalg.LinAlgError:
        raise MechanismError(
            "/parameters",
            "the tangent stiffness is singular here (a limit point): "
            "the state does not depend smoothly on the parameters",
        ) from None
    dz = dw[:n]
    dy = y_z[rows] @ dz + y_p[np.ix_(rows, slots)]
    if target is not None:
        dt = dw[n]
        dy = dy + y_p[rows][:, [t]] * dt
    kinds = [mech.parameters[s].kind for s in slots]
    out_kinds = [mech.graphs.output_kinds[r] for r in rows]
    matrix = (
        dy
        * np.array([mech.nd_per_doc(k) for k in kinds])[None, :]
        / np.array([mech.nd_per_doc(k) for k in out_kinds])[:, None]
    )
    out_names = [names[r] for r in rows]
    units = [[f"{mech.doc_unit(ko)}/{mech.doc_unit(kp)}" for kp in kinds] for ko in out_kinds]
    if target is not None and target[0] in outputs:
        kt = mech.parameters[t].kind
        row = dt * np.array([mech.nd_per_doc(k) for k in kinds]) / mech.nd_per_doc(kt)
        matrix = np.vstack([row[None, :], matrix])
        out_names = [target[0], *out_names]
        units = [[f"{mech.doc_unit(kt)}/{mech.doc_unit(kp)}" for kp in kinds], *units]
    return Sensitivities(list(parameters), out_names, matrix, units)


def optimum_sensitivities(prepared: Prepared, result: StartResult, parameters: list[str]) -> Sensitivities:
    """d(design, objective)/d(parameters) at an optimum, by the KKT conditions on the active set.

    Parameters are numeric fields that are not design variables; a field overridden in a load
    case keeps its override there."""
    problem, nlp = prepared.problem, prepared.nlp
    mech = problem.mechanism
    slots = mech.parameter_indices(parameters, "/parameters")
    for k, (path, slot) in enumerate(zip(parameters, slots)):
        if slot in problem.slots:
            raise MechanismError(f"/parameters/{k}", f"'{path}' is a design variable")
    x = result.x
    H, L_xp, J, g_p, f_p = (np.asarray(a) for a in nlp.kkt(x, prepared.P, result.lam_g))
    dP = np.zeros((len(prepared.P), len(slots)))
    overridden = [set(case.overrides) for case in problem.spec.cases.values()] or [set()]
    for j, (path, slot) in enumerate(zip(parameters, slots)):
        factor = mech.nd_per_doc(mech.parameters[slot].kind)
        for c in range(nlp.n_cases):
            if path not in overridden[c]:
                dP[c * nlp.n_params + slot, j] = factor
    _, g = nlp.evaluate(x, prepared.P)
    g = np.asarray(g).ravel()
    gap = np.minimum(np.abs(g - prepared.lbg), np.abs(g - prepared.ubg))
    active = np.flatnonzero(gap <= ACTIVE_TOLERANCE)  # equilibrium rows are equalities: always in
    at_bound = np.minimum(np.abs(x - prepared.lbx), np.abs(x - prepared.ubx)) <= ACTIVE_TOLERANCE
    free = np.flatnonzero(~at_bound)
    n_free, n_active = len(free), len(active)
    kkt = np.block(
        [[H[np.ix_(free, free)], J[np.ix_(active, free)].T], [J[np.ix_(active, free)], np.zeros((n_active, n_active))]]
    )
    rhs = -np.vstack([L_xp[free] @ dP, g_p[active] @ dP])
    solution = np.linalg.lstsq(kkt, rhs, rcond=None)[0] if np.linalg.cond(kkt) > 1e14 else np.linalg.solve(kkt, rhs)
    dx = np.zeros((len(x), len(slots)))
    dx[free] = solution[:n_free]
    # The optimal objective's total derivative: by the envelope theorem, dL/dp at the optimum.
    lam = result.lam_g
    df = f_p.ravel() @ dP + lam @ (g_p @ dP)
    kinds = [mech.parameters[s].kind for s in slots]
    # dP is per document unit of each parameter, so these rows are too.
    design_rows = dx[: nlp.n_design] * problem.scale[:, None]
    objective_row = df * prepared.objective_scale / problem.output_factor(problem.objective)
    matrix = np.vstack([design_rows, objective_row[None, :]])
    design_kinds = [mech.parameters[s].kind for s in problem.slots]
    units = [[f"{mech.doc_unit(kd)}/{mech.doc_unit(kp)}" for kp in kinds] for kd in design_kinds]
    units.append([f"{mech.doc_unit(problem.objective.kind)}/{mech.doc_unit(kp)}" for kp in kinds])
    return Sensitivities(list(parameters), [*problem.paths, "objective"], matrix, units)
