"""Moreau-Jean time stepping (seed 004 Eqs. 31-39), midpoint rule: the forces at the midpoint
q_M = q + h/2 v, contacts active where the indentation at q_M is >= 0, and per active contact
the impulses (Lambda_N, Lambda_T) of Newton's impact law with Coulomb friction, solved
exactly: no impulse if the free motion already separates fast enough; else sticking
(U_T+ = 0, e_T = 0) if |Lambda_T| <= f_a Lambda_N; else sliding against the stick impulse's
direction with Lambda_T = f_d Lambda_N. Several contacts couple through the Delassus matrix
and are solved by Gauss-Seidel sweeps of these exact local solves. The normal velocity is
U_N = Dn.v (positive separating), and the impact law asks U_N+ >= -e_N U_N-."""

from __future__ import annotations

import casadi as ca

from flexmech.models.impacts.model import WORKS, ImpactModel
from flexmech.service.impacts.contact_forces import kinematics

GAUSS_SEIDEL_SWEEPS = 30  # several pairs only: one pair's local solve is exact


def local_solve(W, U_free, target, f_a, f_d):
    """(Lambda_N, Lambda_T) of one contact: W the 2x2 Delassus block, U_free its free normal and
    tangent velocities, target = -e_N U_N- the least post-impact normal velocity."""
    need = target - U_free[0]
    det = W[0, 0] * W[1, 1] - W[0, 1] * W[1, 0]
    stick_N = (W[1, 1] * need + W[0, 1] * U_free[1]) / det
    stick_T = (-W[1, 0] * need - W[0, 0] * U_free[1]) / det
    sticks = ca.logic_and(stick_N >= 0, ca.fabs(stick_T) <= f_a * stick_N)
    direction = -ca.sign(stick_T)  # the slip the sticking impulse could not hold
    slide_N = need / (W[0, 0] - direction * f_d * W[0, 1])
    slide_T = -direction * f_d * slide_N
    impacting = need > 0
    lam_N = ca.if_else(impacting, ca.if_else(sticks, stick_N, ca.fmax(slide_N, 0)), 0)
    lam_T = ca.if_else(impacting, ca.if_else(sticks, stick_T, ca.if_else(slide_N > 0, slide_T, 0)), 0)
    return lam_N, lam_T


class _Constrained:
    """The pins' reaction in a step: velocities projected onto G v + g_t = -2 g / h (so that
    the end of the step meets g = 0 to second order), and the constrained inverse mass N = M^-1
    - M^-1 G^T S^-1 G M^-1 (S = G M^-1 G^T) through which contact impulses act."""

    def __init__(self, model: ImpactModel, q_mid, v0, t_mid, p, h):
        self.inverse_mass = 1 / model.mass
        self.count = model.constraints.numel()
        if not self.count:
            return
        G, g_t, _ = model.constraint_rates()
        here = ca.Function("pins", [model.q, model.v, model.t, model.p], [G, g_t, model.constraints])
        self.G, self.g_t, g = here(q_mid, v0, t_mid, p)
        self.target = -self.g_t - 2 * g / h
        self.S = ca.mtimes(self.G * ca.repmat(self.inverse_mass.T, self.count, 1), self.G.T)

    def apply(self, impulse):
        """The velocity change of a generalized impulse, the pins reacting."""
        free = self.inverse_mass * impulse
        if not self.count:
            return free
        return free - self.inverse_mass * ca.mtimes(self.G.T, ca.solve(self.S, ca.mtimes(self.G, free)))

    def project(self, v):
        """v with the pins' impulse that makes G v + g_t = -2 g / h."""
        if not self.count:
            return v
        return v + self.inverse_mass * ca.mtimes(self.G.T, self.reaction(v))

    def reaction(self, v):
        """The pins' impulse (on body `to`) that takes v to the target."""
        if not self.count:
            return ca.SX(0, 1)
        return ca.solve(self.S, self.target - ca.mtimes(self.G, v))


def moreau_step(model: ImpactModel) -> ca.Function:
    """(S = [t, q, v, works (WORKS)], p, h) -> (S', per pair [Lambda_N; Lambda_T; U_N before;
    U_N after] (4P), active (P), the pins' impulses (2 per pin))."""
    n, P = model.bodies.size, len(model.pairs)
    q, v, p = model.q, model.v, model.p
    geometry = kinematics(model)
    drift = ca.vertcat(*[ca.vertcat(pair.normal_drift, pair.tangent_drift) for pair in model.pairs])
    at = ca.Function(
        "at",
        [q, v, model.t, p],
        [
            model.force,
            model.extra,
            model.damping,
            model.load_power,
            ca.vertcat(*[g[0] for g in geometry]),
            ca.horzcat(*[g[3] for g in geometry]),
            ca.horzcat(*[g[4] for g in geometry]),
            drift,
        ],
    )
    S, h = ca.SX.sym("S", 1 + 2 * n + len(WORKS)), ca.SX.sym("h")
    t, q0, v0, works = S[0], S[1 : 1 + n], S[1 + n : 1 + 2 * n], S[1 + 2 * n :]
    q_mid = q0 + h / 2 * v0
    force, extra, damping, power, pen, Dn, Dt, drift = at(q_mid, v0, t + h / 2, p)
    load_force = ca.gradient(power, v0)  # the inputs' power: linear in v, plus the supports' rate
    support_rate = ca.substitute(power, v0, ca.SX.zeros(n))
    pins = _Constrained(model, q_mid, v0, t + h / 2, p, h)
    v_free = pins.project(v0 + h * pins.inverse_mass * force)
    active = [pen[k] >= 0 for k in range(P)]
    lam_N, lam_T = _contact_impulses(model, pins, v_free, v0, Dn, Dt, drift, active)
    v1 = v_free + sum((pins.apply(Dn[:, k] * lam_N[k] + Dt[:, k] * lam_T[k]) for k in range(P)), ca.SX.zeros(n))
    q1 = q_mid + h / 2 * v1
    reaction = pins.reaction(
        v0
        + h * pins.inverse_mass * force
        + pins.inverse_mass * sum((Dn[:, k] * lam_N[k] + Dt[:, k] * lam_T[k] for k in range(P)), ca.SX.zeros(n))
    )
    W_N = sum(lam_N[k] * ca.dot(Dn[:, k], v0 + v1) / 2 for k in range(P))  # on the free bodies
    W_T = sum(lam_T[k] * ca.dot(Dt[:, k], v0 + v1) / 2 for k in range(P))
    W_extra = h * ca.dot(extra, v0 + v1) / 2
    W_damping = h * ca.dot(damping, v0 + v1) / 2
    W_pins = ca.dot(reaction, ca.mtimes(pins.G, v0 + v1) / 2) if pins.count else 0  # moving supports
    W_load = h * (ca.dot(load_force, v0 + v1) / 2 + support_rate) + W_pins
    S1 = ca.vertcat(t + h, q1, v1, works + ca.vertcat(W_N, W_T, W_extra, W_damping, W_load))
    before = [ca.dot(Dn[:, k], v0) + drift[2 * k] for k in range(P)]
    after = [ca.dot(Dn[:, k], v1) + drift[2 * k] for k in range(P)]
    return ca.Function(
        "moreau_step",
        [S, p, h],
        [S1, ca.vertcat(*lam_N, *lam_T, *before, *after), ca.vertcat(*active), reaction],
        ["S", "p", "h"],
        ["S1", "impulses", "active", "pins"],
    )


def _contact_impulses(model, pins: _Constrained, v_free, v0, Dn, Dt, drift, active):
    """Each active contact's exact local solve, Gauss-Seidel over several."""
    P = len(model.pairs)
    lam_N, lam_T = [ca.SX(0)] * P, [ca.SX(0)] * P
    for _ in range(1 if P == 1 else GAUSS_SEIDEL_SWEEPS):  # one pair: exact (the pins act through N)
        for k, pair in enumerate(model.pairs):
            d_n, d_t = Dn[:, k], Dt[:, k]
            base = v_free + sum(
                (pins.apply(Dn[:, j] * lam_N[j] + Dt[:, j] * lam_T[j]) for j in range(P) if j != k),
                ca.SX.zeros(v_free.shape),
            )
            n_n, n_t = pins.apply(d_n), pins.apply(d_t)
            W = ca.vertcat(
                ca.horzcat(ca.dot(d_n, n_n), ca.dot(d_n, n_t)), ca.horzcat(ca.dot(d_t, n_n), ca.dot(d_t, n_t))
            )
            U_free = ca.vertcat(ca.dot(d_n, base), ca.dot(d_t, base)) + drift[2 * k : 2 * k + 2]
            target = -pair.restitution * (ca.dot(d_n, v0) + drift[2 * k])
            f_a, f_d = (pair.adherence, pair.sliding) if pair.friction != "none" else (0, 0)
            N_k, T_k = local_solve(W, U_free, target, f_a, f_d)
            lam_N[k] = ca.if_else(active[k], N_k, 0)
            lam_T[k] = ca.if_else(active[k], T_k, 0)
    return lam_N, lam_T
