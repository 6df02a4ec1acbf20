"""Friction of the elastic contact pairs in link dynamics: a regularized law of the slip speed
(Ambrosio's, seed 004 Eq. 26: none below v0, growing to f_d F_N at v1) at the point where the
site's circle meets the object, against the slip of the two bodies' material points there.

The force is a function of the state and its rates, so a time step takes it implicitly and
its Newton rows differentiate it; it is not a potential's, so a run integrates its power, the
friction work of the energy balance. Below v0 (and at rest) it vanishes: a statics solve and
a damped run's rest see none, as the law says. The law's ramp switches regime by the slip
speed itself here (without the hysteresis flags that event-driven runs locate), so the force
is continuous in the slip speed and piecewise smooth.

Speeds: the graphs' lengths are nondimensional and time is in seconds (models.mechanism.Scales);
v0 and v1 are given in m/s, so one m/s is unit("length") / (the document's length unit in m)."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from models.context import AssemblyContext
from models.contact.elastic_pairs import elastic_pairs
from models.contact.laws import FRICTION_LAWS
from models.planar import cross

REGULARIZED = ("ambrosio",)  # friction laws of the slip speed that link dynamics takes


@dataclass
class FrictionNumbers:
    """What a friction law's force reads (models.contact.laws.FrictionLaw.force)."""

    sliding: ca.SX
    v0: ca.SX
    v1: ca.SX


def rubbing(topology) -> bool:
    """Whether the pair's friction acts in link dynamics (an elastic pair with a regularized law)."""
    return topology.potential and topology.friction_law in REGULARIZED


def contact_friction(ctx: AssemblyContext, d: list[ca.SX], rates: list[ca.SX]) -> tuple[list[ca.SX], ca.SX]:
    """(per body the friction's wrench [Fx, Fy, M about its reference point], the friction's
    power) at displacements d and their rates ([vx, vy, omega] of each reference point)."""
    wrenches = [ca.SX.zeros(3) for _ in range(ctx.n_bodies)]
    power = ca.SX(0)
    contacts = ctx.structure.contacts
    if contacts is None or not any(rubbing(pair) for pair in contacts.pairs):
        return wrenches, power
    per_metre_per_second = ctx.unit("length") / ctx.structure.length_unit_si
    for pair in elastic_pairs(ctx, d):
        topology = pair.topology
        if not rubbing(topology):
            continue
        first = contacts.sites[topology.site].body
        second = contacts.objects[topology.object].body
        tangent = ca.vertcat(-pair.normal[1], pair.normal[0])
        slip = ca.dot(tangent, _velocity(ctx, first, pair.point, d, rates) - _velocity(ctx, second, pair.point, d,
                                                                                            rates))
        base = f"{topology.pointer}/friction"
        numbers = FrictionNumbers(ctx.P[f"{base}/sliding"], ctx.P[f"{base}/v0"] * per_metre_per_second,
                                  ctx.P[f"{base}/v1"] * per_metre_per_second)
        law = FRICTION_LAWS[topology.friction_law]
        normal_force = pair.force * ctx.unit("force")
        speed = ca.fabs(slip)
        along = law.force(numbers, slip, normal_force, speed > numbers.v0, speed > numbers.v1)
        force = along * tangent  # on the site's body; the object's body takes the opposite
        for body, sign in ((first, 1), (second, -1)):
            if body is not None:
                arm = pair.point - (ctx.reference(body)[0] + d[body][:2])
                wrenches[body] = wrenches[body] + sign * ca.vertcat(force, cross(arm, force))
        power = power + along * slip
    return wrenches, power


def _velocity(ctx: AssemblyContext, body: int | None, point: ca.SX, d: list[ca.SX], rates: list[ca.SX]) -> ca.SX:
    """The velocity of body's material point at `point` (zero for the world)."""
    if body is None:
        return ca.SX.zeros(2)
    arm = point - (ctx.reference(body)[0] + d[body][:2])
    omega = rates[body][2]
    return rates[body][:2] + omega * ca.vertcat(-arm[1], arm[0])
