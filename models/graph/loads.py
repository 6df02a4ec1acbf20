"""External loads on bodies: forces at points (fixed global direction: dead loads), moments,
and under gravity the weight of every body with mass, at its mass centre.

applied_wrenches gives them as [Fx, Fy, M about the reference point] per body (the residual
form); load_potential is minus their work from the undeformed state (the energy form), so
that its gradient in the body displacements is minus the applied wrenches. Both include the
contact pairs with an elastic law (models.contact.elastic_pairs): their forces come from a
potential, so every form sees them alike.
"""

from __future__ import annotations

import casadi as ca

from flexmech.models.contact.elastic_pairs import contact_potential, contact_wrenches
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.planar import cross


def _center_of_mass(ctx: AssemblyContext, b: int, center: bool) -> ca.SX:
    if not center:
        return ca.SX.zeros(2)
    return ctx.P.vec(f"/bodies/{ctx.structure.bodies[b]}/center_of_mass")


def dead_loads(ctx: AssemblyContext):
    """(body, local point in body axes, force (2,)) of every force and weight, and (body,
    moment) of every moment."""
    s, P = ctx.structure, ctx.P
    forces, moments = [], []
    for load in s.loads:
        base = f"/loads/{load.name}"
        if load.kind == "force":
            forces.append((load.body, ctx.local_point(load.body, base, load.location), P.vec(f"{base}/force")))
        else:
            moments.append((load.body, P[f"{base}/moment"]))
    if s.gravity:
        g = P.vec("/gravity")
        for m in s.masses:
            mass = P[f"/bodies/{s.bodies[m.body]}/mass"]
            forces.append((m.body, _center_of_mass(ctx, m.body, m.center), mass * g))
    return forces, moments


def applied_wrenches(ctx: AssemblyContext, d: list[ca.SX]) -> list[ca.SX]:
    """External wrenches [Fx, Fy, M about the reference point] per body."""
    wrenches = [ca.SX.zeros(3) for _ in range(ctx.n_bodies)]
    forces, moments = dead_loads(ctx)
    for b, local, F in forces:
        arm = ctx.arm(b, local, d)
        wrenches[b] = wrenches[b] + ca.vertcat(F, cross(arm, F))
    for b, M in moments:
        wrenches[b] = wrenches[b] + ca.vertcat(0, 0, M)
    return [wrench + contact for wrench, contact in zip(wrenches, contact_wrenches(ctx, d))]


def load_potential(ctx: AssemblyContext, d: list[ca.SX]) -> ca.SX:
    """Minus the work of the dead loads from the undeformed state to displacements d."""
    zero = [ca.SX.zeros(3) for _ in range(ctx.n_bodies)]
    forces, moments = dead_loads(ctx)
    work = ca.SX(0)
    for b, local, F in forces:
        work = work + ca.dot(F, d[b][:2] + ctx.arm(b, local, d) - ctx.arm(b, local, zero))
    for b, M in moments:
        work = work + M * d[b][2]
    return contact_potential(ctx, d) - work


def kinetic_energy(ctx: AssemblyContext, d: list[ca.SX], v: list[ca.SX]) -> ca.SX:
    """Kinetic energy of the bodies with mass for displacements d and velocities v (per body
    [vx, vy, omega] of the reference point)."""
    return sum((T for _, T in body_kinetic_energies(ctx, d, v)), ca.SX(0))


def body_kinetic_energies(ctx: AssemblyContext, d: list[ca.SX], v: list[ca.SX]) -> list[tuple[int, ca.SX]]:
    """(body, its kinetic energy) of every body with mass: a point mass at the mass centre, or
    with the inertia about the reference point when given."""
    s, P = ctx.structure, ctx.P
    out = []
    for m in s.masses:
        name = s.bodies[m.body]
        mass = P[f"/bodies/{name}/mass"]
        arm = ctx.arm(m.body, _center_of_mass(ctx, m.body, m.center), d)
        speed, omega = v[m.body][:2], v[m.body][2]
        inertia = P[f"/bodies/{name}/inertia"] if m.inertia else mass * ca.dot(arm, arm)
        out.append(
            (m.body, 0.5 * mass * ca.dot(speed, speed) + mass * omega * cross(arm, speed) + 0.5 * inertia * omega**2)
        )
    return out


def mass_centres(ctx: AssemblyContext, d: list[ca.SX]) -> list[tuple[int, ca.SX, ca.SX]]:
    """(body, mass, position of its mass centre) of every body with mass, displaced by d."""
    s = ctx.structure
    return [
        (
            m.body,
            ctx.P[f"/bodies/{s.bodies[m.body]}/mass"],
            ctx.reference(m.body)[0] + d[m.body][:2] + ctx.arm(m.body, _center_of_mass(ctx, m.body, m.center), d),
        )
        for m in s.masses
    ]
