"""The forces of the elastic contact pairs in link dynamics beyond their potential
(models.contact.elastic_pairs): friction, and the damping of the damped normal laws.

Both act at the point C where the site's circle meets the object, on the slip and the
approach of the two bodies' material points there (relative velocity dv = v_site(C) -
v_object(C), tangent t, normal n from the object to the site):

  friction   a regularized law of the slip speed t.dv (Ambrosio's, seed 004 Eq. 26: none below
             v0, growing to f_d F_N at v1), along t;
  damping    the law's force at the indentation rate qdot = -n.dv less its elastic part K q^n:
             Hunt-Crossley, Lankarani-Nikravesh and Flores, K q^n d qdot / qdot_minus with
             qdot_minus the approach speed at the contact's onset (the run locates each onset
             and sets it: service.dynamics.onsets); the total never pulls.

Each is a function of the state and its rates, so a time step takes it implicitly and its
Newton rows differentiate it; none is a potential's, so a run integrates their powers (the
friction's work and the contacts' damping work of the energy balance). At rest both vanish:
the equilibrium solve sees the elastic part alone, as the laws say. The friction's ramp
switches regime by the slip speed itself here (without the hysteresis flags that event-driven
runs locate), so it is continuous in the slip speed and piecewise smooth.

Units: the graphs' lengths and forces are nondimensional and time is in seconds
(models.graph.mechanism.Scales); the normal laws read the document's units (K, q and qdot in its
force and length per second), v0 and v1 are given in m/s."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from flexmech.models.contact.elastic_pairs import DAMPED_LAWS, ElasticPair, elastic_pairs, law_numbers
from flexmech.models.contact.laws import FRICTION_LAWS, NORMAL_LAWS
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.planar import cross

REGULARIZED = ("ambrosio",)  # friction laws of the slip speed that link dynamics takes


@dataclass
class FrictionNumbers:
    """What a friction law's force reads (models.contact.laws.FrictionLaw.force)."""

    sliding: ca.SX
    v0: ca.SX
    v1: ca.SX


@dataclass
class PairForces:
    wrenches: list[ca.SX]  # per body [Fx, Fy, M about its reference point]
    friction_power: ca.SX
    damping_power: ca.SX
    normal_forces: dict[str, ca.SX]  # per damped pair, its whole normal force (document units)


def rubbing(topology) -> bool:
    """Whether the pair's friction acts in link dynamics (an elastic pair with a regularized law)."""
    return topology.potential and topology.friction_law in REGULARIZED


def acting(topology) -> bool:
    """Whether the pair has a force beyond its potential in link dynamics."""
    return rubbing(topology) or (topology.potential and topology.normal_law in DAMPED_LAWS)


def contact_forces(ctx: AssemblyContext, d: list[ca.SX], rates: list[ca.SX]) -> PairForces:
    """The pairs' friction and damping at displacements d and their rates ([vx, vy, omega] of
    each reference point)."""
    out = PairForces([ca.SX.zeros(3) for _ in range(ctx.n_bodies)], ca.SX(0), ca.SX(0), {})
    contacts = ctx.structure.contacts
    if contacts is None or not any(acting(pair) for pair in contacts.pairs):
        return out
    unit_length, unit_force = ctx.unit("length"), ctx.unit("force")
    for pair in elastic_pairs(ctx, d):
        topology = pair.topology
        if not acting(topology):
            continue
        bodies = (contacts.sites[topology.site].body, contacts.objects[topology.object].body)
        dv = _velocity(ctx, bodies[0], pair.point, d, rates) - _velocity(ctx, bodies[1], pair.point, d, rates)
        tangent = ca.vertcat(-pair.normal[1], pair.normal[0])
        force, whole = ca.SX.zeros(2), pair.force  # on the site's body (nondimensional), the object's the opposite
        if topology.normal_law in DAMPED_LAWS:
            qdot = -ca.dot(pair.normal, dv) / unit_length  # document length per second
            law = NORMAL_LAWS[topology.normal_law]
            whole = law.force(
                law_numbers(ctx, topology),
                ca.fmax(pair.indentation, 0.0),
                qdot,
                ctx.P[f"{topology.pointer}/normal/onset_speed"],
            )
            extra = (whole - pair.force) * unit_force
            force = force + extra * pair.normal
            out.damping_power = out.damping_power - extra * qdot * unit_length
            out.normal_forces[topology.name] = whole
        if rubbing(topology):  # on the whole normal force
            along, slip = _friction(ctx, pair, ca.dot(tangent, dv), whole * unit_force)
            force = force + along * tangent
            out.friction_power = out.friction_power + along * slip
        for body, sign in zip(bodies, (1, -1)):
            if body is not None:
                arm = pair.point - (ctx.reference(body)[0] + d[body][:2])
                out.wrenches[body] = out.wrenches[body] + sign * ca.vertcat(force, cross(arm, force))
    return out


def _friction(ctx: AssemblyContext, pair: ElasticPair, slip: ca.SX, normal_force: ca.SX) -> tuple[ca.SX, ca.SX]:
    """(the friction force along the tangent, nondimensional; the slip speed)."""
    topology = pair.topology
    per_metre_per_second = ctx.unit("length") / ctx.structure.length_unit_si
    base = f"{topology.pointer}/friction"
    numbers = FrictionNumbers(
        ctx.P[f"{base}/sliding"], ctx.P[f"{base}/v0"] * per_metre_per_second, ctx.P[f"{base}/v1"] * per_metre_per_second
    )
    speed = ca.fabs(slip)
    law = FRICTION_LAWS[topology.friction_law]
    return law.force(numbers, slip, normal_force, speed > numbers.v0, speed > numbers.v1), slip


def _velocity(ctx: AssemblyContext, body: int | None, point: ca.SX, d: list[ca.SX], rates: list[ca.SX]) -> ca.SX:
    """The velocity of body's material point at `point` (zero for the world)."""
    if body is None:
        return ca.SX.zeros(2)
    arm = point - (ctx.reference(body)[0] + d[body][:2])
    omega = rates[body][2]
    return rates[body][:2] + omega * ca.vertcat(-arm[1], arm[0])
