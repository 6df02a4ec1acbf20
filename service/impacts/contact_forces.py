"""The contact quantities of an impact model in its own symbols (q, v, p): per pair the
indentation, its rate, the slip speed v_T and the generalized directions of unit normal and
tangent forces; and the regularized contact forces the event-driven models apply."""

from __future__ import annotations

import casadi as ca

from flexmech.models.impacts.model import ImpactModel


def kinematics(model: ImpactModel) -> list[tuple]:
    """(indentation, rate, v_T, Dn, Dt) per pair; a driven body's motion adds to the rates."""
    v = model.v
    return [
        (
            pair.indentation,
            -(ca.dot(pair.normal_direction, v) + pair.normal_drift),
            ca.dot(pair.tangent_direction, v) + pair.tangent_drift,
            pair.normal_direction,
            pair.tangent_direction,
        )
        for pair in model.pairs
    ]


def regularized_forces(model: ImpactModel, geometry, contact, beyond_v0, beyond_v1, impact_speed) -> list[tuple]:
    """(F_N, F_T) per pair for the event-driven models, zero out of contact."""
    forces = []
    for k, (pair, (pen, rate, v_T, _, _)) in enumerate(zip(model.pairs, geometry)):
        speed = ca.fmax(impact_speed[k], 1e-300)  # out of contact it is 0: keep 0 * F finite
        F_N = ca.if_else(contact[k], pair.normal_law.force(pair, pen, rate, speed), 0)
        F_T = ca.if_else(contact[k], 1, 0) * pair.friction_law.force(pair, v_T, F_N, beyond_v0[k], beyond_v1[k])
        forces.append((F_N, F_T))
    return forces
