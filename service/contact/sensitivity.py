"""Sensitivities of a contact state: at a converged state, on its active set (and with its
friction directions and sticking pairs held), the KKT system F(v, p) = 0 gives
dv/dp = -F_v^-1 F_p, and every contact output (forces, contact points, site parameters, the
structure's outputs) follows: dy/dp = y_v dv/dp + y_p. A friction coefficient enters through the
slipping rows' factor phi = mu sigma, an input of F and y: F_p and y_p carry its part, F_phi
dphi/dp and y_phi dphi/dp (without it, the derivatives in mu came out 0). At a pair about to
change state (touching with a vanishing force, or apart by a vanishing gap) the derivatives
are one-sided: none is given, and the answer says which pair and why."""

from __future__ import annotations

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.service.contact.kkt import inequality_values, split
from flexmech.service.contact.problem import ContactProblem
from flexmech.service.contact.solve import ContactState
from flexmech.service.design.sensitivity_table import Sensitivities

WEAK = 1e-8
# a gap (nondimensional) below which a pair is about to touch: the solve's accuracy (an open
# pair at its onset shows 2e-7)
TOUCHING = 1e-6


def contact_sensitivities(
    mech: Mechanism,
    problem: ContactProblem,
    state: ContactState,
    parameters: list[str],
    outputs: list[str],
    pointer: str = "/sensitivities",
) -> tuple[Sensitivities, list[str]]:
    """d(outputs)/d(parameters) in document units, and warnings."""
    slots = mech.parameter_indices(parameters, f"{pointer}/parameters")
    rows = []
    for k, name in enumerate(outputs):
        if name not in problem.output_names:
            raise MechanismError(
                f"{pointer}/outputs/{k}",
                f"unknown output '{name}' (contact outputs are "
                "contacts.<pair>.force_x, force_y, normal_force, friction_force, point_x, point_y, "
                "site_parameter, and the mechanism's outputs)",
            )
        rows.append(problem.output_names.index(name))
    out_kinds = [problem.output_kinds[r] for r in rows]
    in_kinds = [mech.parameter_kind(path) for path in parameters]
    factor = np.array([[mech.nd_per_doc(ki) / mech.nd_per_doc(ko) for ki in in_kinds] for ko in out_kinds])
    units = [[f"{mech.doc_unit(ko)}/{mech.doc_unit(ki)}" for ki in in_kinds] for ko in out_kinds]
    boundary = _at_a_state_change(problem, state)
    matrix = np.full(factor.shape, np.nan)
    if not boundary:
        try:
            matrix = _derivatives(mech, problem, state, slots, rows) * factor
        except np.linalg.LinAlgError:
            boundary = [
                "the KKT system is singular at this state (contact rows that do not determine their "
                "forces): no derivative is given"
            ]
    return Sensitivities(list(parameters), list(outputs), matrix, units, boundary), boundary


def _derivatives(
    mech: Mechanism, problem: ContactProblem, state: ContactState, slots: list[int], rows: list[int]
) -> np.ndarray:
    """d(outputs[rows]) / d(p[slots]), nondimensional, on the state's active set."""
    mode = state.mode
    arguments = mode.arguments(state.v, state.p)
    phi_p = friction_rates(mech, problem, state, slots)
    F_v = np.asarray(problem.kkt(**arguments)["J"], dtype=float)
    terms = problem.kkt_parameters(**arguments)
    F_p = np.asarray(terms["Fp"], dtype=float)[:, slots] + np.asarray(terms["Fphi"], dtype=float) @ phi_p
    dv = -np.linalg.solve(F_v, F_p)
    jac = problem.outputs_jacobian(v=state.v, p=state.p, phi=mode.phi, stick=mode.stick, weights=mode.weights)
    y_v = np.asarray(jac["y_v"], dtype=float)[rows]
    y_p = np.asarray(jac["y_p"], dtype=float)[rows][:, slots] + np.asarray(jac["y_phi"], dtype=float)[rows] @ phi_p
    return y_v @ dv + y_p


def friction_rates(mech: Mechanism, problem: ContactProblem, state: ContactState, slots: list[int]) -> np.ndarray:
    """d phi / d p[slots] (rows x slots). A slipping row's friction factor phi = mu sigma moves
    with its pair's friction coefficient mu (sigma, its direction, held); a sticking pair's
    force is what holds it (tau, an unknown), whatever mu, and a frictionless row has none."""
    mode = state.mode
    out = np.zeros((len(mode.phi), len(slots)))
    pairs = problem.structure.contacts.pairs
    coefficient = {mech.parameter_index(pair.friction_pointer): j for j, pair in enumerate(pairs)}
    for column, slot in enumerate(slots):
        j = coefficient.get(slot)
        if j is None or mode.stick[j] > 0:
            continue
        for k, row_pair in enumerate(problem.row_pairs):
            if row_pair == j:
                out[problem.n_element_in + k, column] = state.sigma[j]
    return out


def _at_a_state_change(problem: ContactProblem, state: ContactState) -> list[str]:
    """The pairs about to change state, where the outputs have one-sided derivatives only:
    touching with a vanishing force (a multiplier below WEAK of the largest: about to
    open), or apart by a vanishing gap (below TOUCHING: about to touch)."""
    lam = split(problem, state.v).lam_in
    active = state.mode.active > 0.5
    gaps = inequality_values(problem, split(problem, state.v).w, state.p)
    largest = float(np.abs(lam[active]).max(initial=0.0))
    weak = active & (lam < WEAK * max(largest, 1e-300))
    near = ~active & (gaps < TOUCHING)
    pairs = problem.structure.contacts.pairs

    def named(rows) -> set[str]:
        return {
            pairs[problem.row_pairs[k - problem.n_element_in]].name
            for k in np.flatnonzero(rows)
            if k >= problem.n_element_in
        }

    opening, touching = named(weak), named(near) - named(active)  # a touching pair is about to open, if at all
    return [
        f"pair '{name}' {what}: the derivatives are one-sided, none is given"
        for names, what in (
            (opening, "touches with a vanishing force (about to open)"),
            (touching, "is apart by a vanishing gap (about to touch)"),
        )
        for name in sorted(names)
    ]
