"""The dynamics form: the energy form's unknowns x with their rates v, the kinetic energy
T(x, v) of every mass (bodies with mass; elements' InertiaPoints: a link's mass and the
rotary inertia of its sections, lumped at its quadrature points), and Lagrange's equations

    R(x, v, a, lam) = d/dt (dT/dv) - dT/dx + dV/dx + G^T lam = M(x) a + (d(dT/dv)/dx) v - dT/dx
                      + dV/dx + G^T lam,          g(x) = 0,

with G = dg/dx, the joints' and end conditions' equalities. A mass-proportional damping
adds alpha M v. Prescribed body coordinates do not move here (their values are parameters).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from models.forms import symbolic_energy
from models.loads import kinetic_energy
from models.structure import Structure


@dataclass(frozen=True)
class DynamicsForm:
    unknowns: tuple[str, ...]
    n_equalities: int
    x_in_state: tuple[int, ...]
    multipliers_in_state: tuple[int, ...]
    equations: ca.Function  # (x, v, a, lam, p, damping) -> R
    constraints: ca.Function  # (x, p) -> g
    constraint_jacobian: ca.Function  # (x, p) -> G = dg/dx
    constraint_drift: ca.Function  # (x, v, p) -> (dG/dx v) v: g's second derivative less G a
    energies: ca.Function  # (x, v, p) -> (T, V)
    mass: ca.Function  # (x, p) -> M
    has_mass: bool  # some mass at all


def dynamics_form(structure: Structure) -> DynamicsForm:
    s = symbolic_energy(structure)
    x, p = s.x, s.ctx.p
    n = x.numel()
    v, a = ca.SX.sym("v", n), ca.SX.sym("a", n)
    damping = ca.SX.sym("damping")
    body_rates = [ca.jtimes(d_b, x, v) for d_b in s.d]
    T = kinetic_energy(s.ctx, s.d, body_rates)
    if s.inertia:  # every point's velocity in one forward sweep: the positions share their sums
        speeds = ca.reshape(ca.jtimes(ca.vertcat(*[q.position for q in s.inertia]), x, v), 2, len(s.inertia))
        masses = ca.vertcat(*[q.mass for q in s.inertia])
        T = T + 0.5 * ca.dot(masses, ca.sum1(speeds**2).T)
        turning = [q for q in s.inertia if q.angle is not None and q.rotary is not None]
        if turning:
            rates = ca.jtimes(ca.vertcat(*[q.angle for q in turning]), x, v)
            T = T + 0.5 * ca.dot(ca.vertcat(*[q.rotary for q in turning]), rates**2)
    g = ca.vertcat(*[row for _, row in s.equalities]) if s.equalities else ca.SX(0, 1)
    lam = ca.SX.sym("lam", g.numel())
    momentum = ca.gradient(T, v)
    M = ca.jacobian(momentum, v)
    R = (ca.mtimes(M, a) + ca.jtimes(momentum, x, v) - ca.gradient(T, x) + ca.gradient(s.potential, x)
         + ca.mtimes(ca.jacobian(g, x).T, lam) + damping * ca.mtimes(M, v))
    drift = ca.jtimes(ca.jtimes(g, x, v), x, v)
    return DynamicsForm(
        tuple(s.names), g.numel(), tuple(s.x_in_state), tuple(s.multipliers_in_state),
        ca.Function("equations", [x, v, a, lam, p, damping], [R], ["x", "v", "a", "lam", "p", "damping"], ["R"]),
        ca.Function("constraints", [x, p], [g], ["x", "p"], ["g"]),
        ca.Function("constraint_jacobian", [x, p], [ca.jacobian(g, x)], ["x", "p"], ["G"]),
        ca.Function("constraint_drift", [x, v, p], [drift], ["x", "v", "p"], ["drift"]),
        ca.Function("energies", [x, v, p], [T, s.potential], ["x", "v", "p"], ["T", "V"]),
        ca.Function("mass", [x, p], [M], ["x", "p"], ["M"]),
        bool(s.inertia) or bool(structure.masses))
