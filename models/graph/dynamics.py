"""The dynamics form: the energy form's unknowns x with their rates v, the kinetic energy
T of every mass (bodies with mass; elements' InertiaPoints: a link's mass and the rotary
inertia of its sections, lumped at its quadrature points), and Lagrange's equations

    R(x, v, a, lam) = d/dt (dT/dv) - dT/dx + dV/dx + G^T lam + alpha M v = 0,   g(x) = 0,

with G = dg/dx, the joints' and end conditions' equalities, and alpha a mass-proportional
damping. Prescribed motions are parameters that move: `moving` names them (indices into p),
their rates pdot and accelerations pddot are inputs, and the masses they carry make T
depend on pdot (a spinning hub drags its rod). Q is the generalized force each moving
parameter needs (its reaction), so that Q . pdot is the power the motion puts in.

The loads that vary in time enter V linearly in their parameters: V_held removes them
(V - p_k dV/dp_k over the masked k), and their power is -p_k d2V/dx dp_k . v, so that
T + V_held - (work of loads and motions) + (work of damping) is constant.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from flexmech.models.graph.forms import symbolic_energy
from flexmech.models.graph.loads import kinetic_energy
from flexmech.models.graph.structure import Structure


@dataclass(frozen=True)
class DynamicsForm:
    unknowns: tuple[str, ...]
    n_equalities: int
    x_in_state: tuple[int, ...]
    multipliers_in_state: tuple[int, ...]
    moving: tuple[int, ...]  # indices of p that are prescribed motions in time
    equations: ca.Function  # (x, v, a, lam, p, pdot, pddot, damping) -> R
    constraints: ca.Function  # (x, p) -> g
    constraint_jacobian: ca.Function  # (x, p) -> G = dg/dx
    constraint_drift: ca.Function  # (x, v, p, pdot, pddot) -> d2g/dt2 - G a
    energies: ca.Function  # (x, v, p, pdot) -> (T, V)
    mass: ca.Function  # (x, p) -> M
    motion_forces: ca.Function  # (x, v, a, lam, p, pdot, pddot) -> Q, one per moving parameter
    load_terms: ca.Function  # (x, v, p, mask) -> (power of the masked loads, V_held)
    has_mass: bool  # some mass at all


def _rate(expr: ca.SX, pairs) -> ca.SX:
    """d expr / dt along the (symbol, rate) pairs: one forward sweep each."""
    out = ca.SX.zeros(expr.shape)
    for symbol, rate in pairs:
        if symbol.numel():
            out = out + ca.jtimes(expr, symbol, rate)
    return out


def dynamics_form(structure: Structure, moving: tuple[int, ...] = ()) -> DynamicsForm:
    """The inertia of the elements' points is written as sum m_q J_q^T (acceleration of q), the
    accelerations by forward sweeps and J^T by one reverse sweep: Lagrange's equations of
    point masses without differentiating T twice (several times fewer operations)."""
    s = symbolic_energy(structure)
    x, p = s.x, s.ctx.p
    n, n_p = x.numel(), p.numel()
    v, a = ca.SX.sym("v", n), ca.SX.sym("a", n)
    pdot, pddot = ca.SX.sym("pdot", len(moving)), ca.SX.sym("pddot", len(moving))
    p_rate = ca.SX.zeros(n_p)
    for k, index in enumerate(moving):
        p_rate[index] = pdot[k]
    damping = ca.SX.sym("damping")
    mask = ca.SX.sym("mask", n_p)
    rates = [(x, v), (p, p_rate)] if moving else [(x, v)]
    second = [(x, v), (p, p_rate), (pdot, pddot)] if moving else [(x, v)]

    def velocity(expr):  # x moving at v, the prescribed parameters at pdot
        return _rate(expr, rates)

    def acceleration(expr):  # d2 expr / dt2, given the accelerations a and pddot (through pdot's rate)
        return _rate(velocity(expr), second) + ca.jtimes(expr, x, a)

    T, inertia_x, inertia_p, mass_times_v = _inertia(s, moving, v, a, pdot, velocity, acceleration, second)
    g = ca.vertcat(*[row for _, row in s.equalities]) if s.equalities else ca.SX(0, 1)
    lam = ca.SX.sym("lam", g.numel())
    G = ca.jacobian(g, x)
    R = inertia_x + ca.gradient(s.potential, x) + ca.mtimes(G.T, lam) + damping * mass_times_v
    drift = _rate(velocity(g), second)
    Q = _motion_forces(inertia_p, s.potential, lam, g, p, moving)
    M = ca.jacobian(mass_times_v, v)
    power, held = _load_terms(s.potential, x, v, p, mask)
    return DynamicsForm(
        tuple(s.names),
        g.numel(),
        tuple(s.x_in_state),
        tuple(s.multipliers_in_state),
        tuple(moving),
        ca.Function(
            "equations",
            [x, v, a, lam, p, pdot, pddot, damping],
            [R],
            ["x", "v", "a", "lam", "p", "pdot", "pddot", "damping"],
            ["R"],
        ),
        ca.Function("constraints", [x, p], [g], ["x", "p"], ["g"]),
        ca.Function("constraint_jacobian", [x, p], [G], ["x", "p"], ["G"]),
        ca.Function("constraint_drift", [x, v, p, pdot, pddot], [drift], ["x", "v", "p", "pdot", "pddot"], ["drift"]),
        ca.Function("energies", [x, v, p, pdot], [T, s.potential], ["x", "v", "p", "pdot"], ["T", "V"]),
        ca.Function("mass", [x, p], [M], ["x", "p"], ["M"]),
        ca.Function(
            "motion_forces", [x, v, a, lam, p, pdot, pddot], [Q], ["x", "v", "a", "lam", "p", "pdot", "pddot"], ["Q"]
        ),
        ca.Function("load_terms", [x, v, p, mask], [power, held], ["x", "v", "p", "mask"], ["power", "V_held"]),
        bool(s.inertia) or bool(structure.masses),
    )


def _motion_forces(inertia_p: ca.SX, potential: ca.SX, lam: ca.SX, g: ca.SX, p: ca.SX, moving) -> ca.SX:
    """Q: per moving parameter the generalized force its motion needs (its reaction)."""
    if not moving:
        return ca.SX(0, 1)
    needed = inertia_p + ca.gradient(potential + ca.dot(lam, g), p)
    return ca.vertcat(*[needed[index] for index in moving])


def _load_terms(potential: ca.SX, x: ca.SX, v: ca.SX, p: ca.SX, mask: ca.SX) -> tuple[ca.SX, ca.SX]:
    """(the power of the masked loads, V_held: V without them), V being linear in their parameters."""
    grad_x = ca.gradient(potential, x)
    power = -ca.dot(ca.jtimes(grad_x, p, mask * p), v)
    held = potential - ca.dot(ca.gradient(potential, p), mask * p)
    return power, held


def _inertia(s, moving, v, a, pdot, velocity, acceleration, second):
    """(T, the inertia forces on x and on p, M v) of the bodies and the elements' points."""
    x, p = s.x, s.ctx.p
    n_p = p.numel()
    # bodies with mass: Lagrange's equations of their kinetic energy (few coordinates)
    T_bodies = kinetic_energy(s.ctx, s.d, [velocity(d_b) for d_b in s.d])
    momentum = ca.gradient(T_bodies, v)
    inertia_x = ca.mtimes(ca.jacobian(momentum, v), a) + _rate(momentum, second) - ca.gradient(T_bodies, x)
    inertia_p = ca.SX.zeros(n_p)
    if moving:
        momentum_p = ca.gradient(T_bodies, pdot)
        drag = ca.mtimes(ca.jacobian(momentum_p, v), a) + _rate(momentum_p, second)
        for k, index in enumerate(moving):
            inertia_p[index] = drag[k]
        inertia_p = inertia_p - ca.gradient(T_bodies, p)
    T, mass_times_v = T_bodies, ca.mtimes(ca.jacobian(momentum, v), v)
    points = s.inertia
    if points:  # the elements' point masses and rotary inertias: sum m J^T (d2 position / dt2)
        where = ca.vertcat(*[q.position for q in points])
        masses = ca.repmat(ca.vertcat(*[q.mass for q in points]).T, 2, 1).reshape((-1, 1))
        turning = [q for q in points if q.angle is not None and q.rotary is not None]
        if turning:
            where = ca.vertcat(where, *[q.angle for q in turning])
            masses = ca.vertcat(masses, *[q.rotary for q in turning])
        speed = velocity(where)
        weighted = masses * acceleration(where)
        inertia_x = inertia_x + ca.jtimes(where, x, weighted, True)
        if moving:
            inertia_p = inertia_p + ca.jtimes(where, p, weighted, True)
        T = T + 0.5 * ca.dot(masses, speed**2)
        mass_times_v = mass_times_v + ca.jtimes(where, x, masses * ca.jtimes(where, x, v), True)
    return T, inertia_x, inertia_p, mass_times_v
