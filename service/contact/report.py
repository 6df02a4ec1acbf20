"""A contact state as data in the document's units: per pair its state, the force on the
site (normal and friction parts), the contact point and where along the site it is, the
gap; the structure's outputs (reactions included) at the state; diagnostics."""

from __future__ import annotations

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.service.contact.kkt import inequality_values, split
from flexmech.service.contact.problem import ContactProblem
from flexmech.service.contact.solve import ContactState, PenetratingStart
from flexmech.service.units import outputs_in_doc_units


def friction_coefficients(mech: Mechanism, problem: ContactProblem, p: np.ndarray | None = None) -> np.ndarray:
    p = mech.p() if p is None else p
    return np.array([p[mech.parameter_index(pair.friction_pointer)] for pair in problem.structure.contacts.pairs])


def pair_values(problem: ContactProblem, state: ContactState) -> dict[str, np.ndarray]:
    """Nondimensional per-pair results of a state (pair_results, and the gap)."""
    mode = state.mode
    force, normal, tangential, point, along, direction = (
        np.asarray(a, dtype=float) for a in problem.pair_results(state.v, state.p, mode.phi, mode.stick, mode.weights)
    )
    h = inequality_values(problem, split(problem, state.v).w, state.p)[problem.n_element_in :]
    gap = np.full(problem.n_pairs, np.inf)
    for k, pair in enumerate(problem.row_pairs):
        gap[pair] = min(gap[pair], h[k])
    return {
        "force": force.reshape(2, -1),
        "normal_force": normal.ravel(),
        "tangential_force": tangential.ravel(),
        "point": point.reshape(2, -1),
        "along": along.ravel(),
        "gap": gap,
        "normal": direction.reshape(2, -1),
    }


def pairs_report(mech: Mechanism, problem: ContactProblem, state: ContactState) -> dict[str, dict]:
    values = pair_values(problem, state)
    to_force = 1.0 / mech.nd_per_doc("force")
    to_length = 1.0 / mech.nd_per_doc("length")
    out = {}
    for j, pair in enumerate(problem.structure.contacts.pairs):
        touching = state.pair_states[j] != "open"
        force = values["force"][:, j] * to_force
        out[pair.name] = {
            "state": state.pair_states[j],
            "force": force.tolist() if touching else [0.0, 0.0],
            "normal_force": values["normal_force"][j] * to_force if touching else 0.0,
            "friction_force": values["tangential_force"][j] * to_force if touching else 0.0,
            "normal": values["normal"][:, j].tolist() if touching else None,
            "point": (values["point"][:, j] * to_length).tolist() if touching else None,
            "site_parameter": values["along"][j] * to_length if touching else None,
            "gap": values["gap"][j] * to_length,
        }
    return out


def structure_outputs(mech: Mechanism, problem: ContactProblem, state: ContactState) -> dict[str, float]:
    """The mechanism's outputs at the state (document units), its reactions and link start
    wrenches with the contact forces they carry (service.contact.wrenches)."""
    mode = state.mode
    y = np.asarray(problem.outputs(state.v, state.p, mode.phi, mode.stick, mode.weights), dtype=float).ravel()
    first = len(problem.output_names) - len(mech.graphs.output_names)
    return outputs_in_doc_units(mech, y[first:])


def state_report(mech: Mechanism, problem: ContactProblem, state: ContactState) -> dict:
    return {
        "status": state.status,
        "message": state.message,
        "iterations": state.iterations,
        "seconds": state.seconds,
        "approach_steps": state.approach_steps,
        "kkt_residual": state.kkt_norm / mech.nd_per_doc("force") if np.isfinite(state.kkt_norm) else None,
        "pairs": pairs_report(mech, problem, state),
        "outputs": structure_outputs(mech, problem, state),
    }


def penetration_error(mech: Mechanism, error: PenetratingStart) -> MechanismError:
    contacts = mech.structure.contacts
    pair = contacts.pairs[error.pair]
    site, obj = contacts.sites[pair.site], contacts.objects[pair.object]
    depth = error.depth / mech.nd_per_doc("length")
    return MechanismError(
        f"/document{pair.pointer}",
        f"object '{obj.name}' penetrates site '{site.name}' by "
        f"{depth:.4g} {mech.doc_unit('length')} in the start state (the undeformed mechanism): move "
        "it clear, or let the analysis approach it (penetrating_start: approach)",
    )
