"""Modes about a contact state: the frictionless minimum of the contact analysis (the document's
contact pairs, closed where they press), its closed contacts held as constraints.

In the contact problem's unknowns w = [x; a] (the energy form's x, the separating axes a), its
active-set KKT system's Jacobian (service.contact.kkt_system) at the state has
    K = d(stationarity)/dw: the Hessian of V + lam_eq . g - lam_in . h, so the contact forces'
        curvature terms are in it;
    G = the rows of the equalities, of the active contact rows and of the frozen axes;
the axes carry no mass (they follow); elastic (penalty) laws are already in V, as stiffness."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.service.contact.problem import contact_problem
from flexmech.service.contact.report import penetration_error
from flexmech.service.contact.solve import ContactOptions, PenetratingStart, solve_state
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.vibration.modes import ModalSystem, modal_system
from flexmech.service.vibration.state import check_modal_cost


def contact_system(mech: Mechanism, newton: NewtonOptions, report: dict) -> tuple[ModalSystem, np.ndarray] | None:
    """(the system about the contact state, the residual form's z of its x), or None when the
    state was not found (the report says why)."""
    check_modal_cost(mech)
    if mech.structure.contacts is None:
        raise MechanismError("/at", "the document has no contacts: take at = equilibrium")
    try:
        problem = contact_problem(mech.structure)
        p = mech.p()
        state = solve_state(
            problem,
            p,
            np.zeros(len(problem.structure.contacts.pairs)),
            options=ContactOptions(time_limit=newton.time_limit),
        )
    except PenetratingStart as error:
        raise penetration_error(mech, error) from None
    report.update(status=state.status, message=state.message, iterations=state.iterations, seconds=state.seconds)
    names = [pair.name for pair in problem.structure.contacts.pairs]
    report["contacts"] = dict(zip(names, state.pair_states))
    if not state.converged:
        return None
    n_x, n_w, n_eq = problem.n_x, problem.n_w, problem.n_eq
    J = np.asarray(problem.kkt(**state.mode.arguments(state.v, p))["J"], dtype=float)
    held = [n_w + k for k in range(n_eq)]
    held += [n_w + n_eq + k for k in range(problem.n_in) if state.mode.active[k] > 0.5]
    held += [n_x + k for k in range(problem.n_axes) if state.mode.freeze[k] > 0.5]
    z = problem.to_state(state.v[:n_w], np.zeros(len(problem.multipliers_in_state)))
    base = modal_system(mech, z, p)
    return _widened(base, J[:n_w, :n_w], J[held, :n_w], problem.n_axes), z


def _widened(base: ModalSystem, K: np.ndarray, G: np.ndarray, axes: int) -> ModalSystem:
    """The energy form's system in w = [x; a]: the axes massless, moving no point."""

    def pad(matrix: np.ndarray) -> np.ndarray:
        return np.pad(matrix, ((0, axes), (0, axes)))

    return replace(
        base,
        coordinates=[*base.coordinates, *(f"axis{k}" for k in range(axes))],
        K=K,
        G=G,
        masses=[pad(m) for m in base.masses],
        uniform=np.pad(base.uniform, ((0, axes), (0, 0))),
        point_jacobian=np.pad(base.point_jacobian, ((0, 0), (0, axes))),
        coordinates_set="elements (contact)",
    )
