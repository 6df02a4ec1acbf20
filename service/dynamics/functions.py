"""The CasADi Functions of time integration, per structure, scheme and set of moving
parameters: the dynamics form, one step's residual and Jacobian (for Newton in Python), and
the monitor of energies and powers measured after every step."""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from models.dynamics import DynamicsForm, dynamics_form
from models.structure import Structure
from service.dynamics.schemes import Scheme


@lru_cache(maxsize=16)
def form_of(structure: Structure, moving: tuple[int, ...] = ()) -> DynamicsForm:
    return dynamics_form(structure, moving)


@lru_cache(maxsize=16)
def step_function(structure: Structure, scheme: Scheme, moving: tuple[int, ...] = ()) -> ca.Function:
    """(u = [qdd1; lam1], x, v, a, qdd, h, p1, pdot1, pddot1, damping) -> (F, dF/du, x1, v1, a1)."""
    form = form_of(structure, moving)
    n, m = len(form.unknowns), form.n_equalities
    u = ca.SX.sym("u", n + m)
    qdd1, lam1 = u[:n], u[n:]
    x, v, a, qdd = (ca.SX.sym(name, n) for name in ("x", "v", "a", "qdd"))
    h, damping = ca.SX.sym("h"), ca.SX.sym("damping")
    p = ca.SX.sym("p", form.constraints.size1_in(1))
    pdot, pddot = ca.SX.sym("pdot", len(moving)), ca.SX.sym("pddot", len(moving))
    s = scheme
    a1 = ((1 - s.alpha_f) * qdd1 + s.alpha_f * qdd - s.alpha_m * a) / (1 - s.alpha_m)
    x1 = x + h * v + h**2 * ((0.5 - s.beta) * a + s.beta * a1)
    v1 = v + h * ((1 - s.gamma) * a + s.gamma * a1)
    F = ca.vertcat(form.equations(x1, v1, qdd1, lam1, p, pdot, pddot, damping), form.constraints(x1, p) / (s.beta * h**2))
    return ca.Function("step", [u, x, v, a, qdd, h, p, pdot, pddot, damping], [F, ca.jacobian(F, u), x1, v1, a1],
                       ["u", "x", "v", "a", "qdd", "h", "p", "pdot", "pddot", "damping"], ["F", "J", "x1", "v1", "a1"])


@lru_cache(maxsize=16)
def monitor_function(structure: Structure, moving: tuple[int, ...] = ()) -> ca.Function:
    """(x, v, qdd, lam, p, pdot, pddot, mask, damping) -> (T, V_held, input power, damping power, Q)."""
    form = form_of(structure, moving)
    n, m, n_p = len(form.unknowns), form.n_equalities, form.constraints.size1_in(1)
    x, v, qdd = (ca.SX.sym(name, n) for name in ("x", "v", "qdd"))
    lam, p, mask = ca.SX.sym("lam", m), ca.SX.sym("p", n_p), ca.SX.sym("mask", n_p)
    pdot, pddot = ca.SX.sym("pdot", len(moving)), ca.SX.sym("pddot", len(moving))
    damping = ca.SX.sym("damping")
    T, _ = form.energies(x, v, p, pdot)
    load_power, held = form.load_terms(x, v, p, mask)
    Q = form.motion_forces(x, v, qdd, lam, p, pdot, pddot)
    M = form.mass(x, p)
    input_power = load_power + (ca.dot(Q, pdot) if moving else 0)
    return ca.Function("monitor", [x, v, qdd, lam, p, pdot, pddot, mask, damping],
                       [T, held, input_power, damping * ca.dot(v, ca.mtimes(M, v)), Q])
