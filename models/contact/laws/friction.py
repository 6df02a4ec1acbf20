"""Friction laws: none; Coulomb's (stick and slip, set-valued: the quasi-static solve's slip
against the motion and Moreau-Jean's impulses take it, with adherence f_a and sliding f_d);
Ambrosio's regularized law (seed 004 Eq. 26), a force of the slip speed for event-driven
runs and link dynamics (models.contact.pair_forces)."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from flexmech.models.contact.laws.registry import ANALYSES, FrictionLaw


@dataclass(frozen=True)
class NoFriction(FrictionLaw):
    name: str = "none"
    analyses: frozenset[str] = frozenset(ANALYSES)
    summary: str = "frictionless"

    def force(self, pair, slip_speed, normal_force, beyond_v0, beyond_v1):
        return ca.SX(0)


@dataclass(frozen=True)
class Coulomb(FrictionLaw):
    name: str = "coulomb"
    analyses: frozenset[str] = frozenset({"contact", "moreau"})
    summary: str = "Coulomb's stick and slip: adherence f_a, sliding f_d (set-valued)"


@dataclass(frozen=True)
class Ambrosio(FrictionLaw):
    """None below v0, growing to f_d F_N at v1 (Eq. 26); the regime (|v_T| beyond v0, beyond
    v1) is given by flags that the integrator switches at located events, so the force is
    smooth within a step."""

    name: str = "ambrosio"
    analyses: frozenset[str] = frozenset({"event_driven", "link_dynamics"})
    summary: str = "Ambrosio's regularized law: none below v0, f_d F_N from v1 (Eq. 26)"
    speed_events: bool = True

    def force(self, pair, slip_speed, normal_force, beyond_v0, beyond_v1):
        v0, v1 = pair.v0, pair.v1
        ramp = ca.fmin(ca.fmax((ca.fabs(slip_speed) - v0) / (v1 - v0), 0.0), 1.0)  # flags switch with a hysteresis
        scale = ca.if_else(beyond_v1, 1.0, ca.if_else(beyond_v0, ramp, 0.0))
        return -scale * pair.sliding * normal_force * ca.sign(slip_speed)
