"""Event-driven integration of an impact model: Dormand-Prince 5(4) steps with error control,
and events located by root finding. An event is a sign change of a switching function: a
pair's indentation (contact onset and separation) and, in contact, its slip speed against
Ambrosio's v0 and v1 (stick/slip transitions). Forces follow flags that change only at
located events, so they are smooth within every step.

One call of `event_step` is one trial step, as a state machine: a step whose end violates a
flag starts locating, and the following calls bracket the event time by the Illinois
method on the step size (each a full Dormand-Prince step from the same start) until the
bracket is a few ulps of t or the switching value is below 1e-13 of its scale; the step
then ends just past the event, the flag flips, and a contact onset freezes the impact speed
(the qdot_minus of the laws). A flag that is on switches off HYSTERESIS of its scale beyond
where it switched on, so no event repeats in zero time (a body grazing its surface). Chunks
of calls run in one CasADi call (mapaccum).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from flexmech.models.impacts.model import WORKS, ImpactModel
from flexmech.service.impacts.contact_forces import kinematics, regularized_forces

# Dormand-Prince 5(4): nodes, stages, the fifth-order weights and the embedded fourth-order ones
C = (0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1, 1)
A = (
    (),
    (1 / 5,),
    (3 / 40, 9 / 40),
    (44 / 45, -56 / 15, 32 / 9),
    (19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729),
    (9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656),
    (35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84),
)
B = (35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0)
B_EMBEDDED = (5179 / 57600, 0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100, 1 / 40)
SWITCH_TOLERANCE = 1e-13  # of each switching function's scale
MIN_IMPACT_SPEED = 1e-9  # m/s: the frozen qdot_minus of a grazing onset, so the laws stay finite
HYSTERESIS = 1e-8  # of each switching function's scale
MASKED = -10.0
ERR_FLOOR = 1e-12  # (0.9 / 4)^5 = 6e-4 and below all grow a step fourfold
BAUMGARTE = 50.0  # 1/s: the rate at which the pins' drift (integration error) is pulled back  # a switching value that cannot trigger (friction out of contact)


@dataclass(frozen=True)
class EventLayout:
    """Where each part of the state vector sits."""

    n: int  # coordinates
    P: int  # pairs

    @property
    def y(self) -> slice:  # q, v and the works (normal, friction, turning flexure)
        return slice(1, 1 + 2 * self.n + len(WORKS))

    def at(self, name: str) -> int | slice:
        base = 1 + 2 * self.n + len(WORKS)
        P = self.P
        order = [
            ("h", 1),
            ("contact", P),
            ("beyond_v0", P),
            ("beyond_v1", P),
            ("speed", P),
            ("locating", 1),
            ("h_lo", 1),
            ("G_lo", 1),
            ("h_hi", 1),
            ("G_hi", 1),
            ("side", 1),
            ("accepted", 1),
            ("event", 1),
        ]
        for key, size in order:
            if key == name:
                return (
                    base
                    if size == 1 and key not in ("contact", "beyond_v0", "beyond_v1", "speed")
                    else slice(base, base + size)
                )
            base += size
        raise KeyError(name)

    @property
    def size(self) -> int:
        return 1 + 2 * self.n + len(WORKS) + 1 + 4 * self.P + 8


def rhs_function(model: ImpactModel) -> ca.Function:
    """(q, v, t, contact, beyond_v0, beyond_v1, speed, p) -> (ydot, switching (3P), F_N, F_T, rate,
    v_T, the pins' forces)."""
    P = len(model.pairs)
    q, v, p = model.q, model.v, model.p
    contact, b0, b1, speed = (ca.SX.sym(name, P) for name in ("contact", "beyond_v0", "beyond_v1", "speed"))
    geometry = kinematics(model)
    forces = regularized_forces(model, geometry, contact, b0, b1, speed)
    Q = model.force
    works = [ca.SX(0), ca.SX(0), ca.dot(model.extra, v), ca.dot(model.damping, v), model.load_power]
    switching = []
    for k, (pair, (pen, _rate, v_T, Dn, Dt), (F_N, F_T)) in enumerate(zip(model.pairs, geometry, forces)):
        Q = Q + F_N * Dn + F_T * Dt
        works[0] += F_N * ca.dot(Dn, v)
        works[1] += F_T * ca.dot(Dt, v)
        slip = ca.fabs(v_T)
        # a flag that is on switches off a hair beyond where it switched on (HYSTERESIS): a
        # body grazing the surface, or slipping at v0, would otherwise toggle in zero time
        switching += [
            (pen + HYSTERESIS * pair.length_scale * contact[k]) / pair.length_scale,
            (slip - pair.v0 * (1 - HYSTERESIS * b0[k])) / pair.v0,
            (slip - pair.v1 * (1 - HYSTERESIS * b1[k])) / pair.v1,
        ]
    accelerations, reaction = pinned_accelerations(model, Q)
    pins_power = ca.dot(reaction, ca.mtimes(ca.jacobian(model.constraints, q), v))  # pins on moving supports
    works[WORKS.index("input_work")] += pins_power
    ydot = ca.vertcat(v, accelerations, *works)
    column = [ca.vertcat(*items) for items in zip(*forces)]
    return ca.Function(
        "rhs",
        [q, v, model.t, contact, b0, b1, speed, p],
        [
            ydot,
            ca.vertcat(*switching),
            column[0],
            column[1],
            ca.vertcat(*[g[1] for g in geometry]),
            ca.vertcat(*[g[2] for g in geometry]),
            reaction,
        ],
        ["q", "v", "t", "contact", "beyond_v0", "beyond_v1", "speed", "p"],
        ["ydot", "switching", "F_N", "F_T", "rate", "v_T", "pins"],
    )


def pinned_accelerations(model: ImpactModel, Q: ca.SX) -> tuple[ca.SX, ca.SX]:
    """(a, the pins' forces lambda) of M a = Q + G^T lambda with G a = -gamma - 2 w gdot - w^2 g:
    the pins held at acceleration level, their drift damped critically (Baumgarte, w)."""
    inverse_mass = 1 / model.mass
    if not model.constraints.numel():
        return inverse_mass * Q, ca.SX(0, 1)
    G, g_t, gamma = model.constraint_rates()
    rate = ca.mtimes(G, model.v) + g_t
    S = ca.mtimes(G * ca.repmat(inverse_mass.T, G.size1(), 1), G.T)
    wanted = -gamma - 2 * BAUMGARTE * rate - BAUMGARTE**2 * model.constraints
    reaction = ca.solve(S, wanted - ca.mtimes(G, inverse_mass * Q))
    return inverse_mass * (Q + ca.mtimes(G.T, reaction)), reaction


def violations(model: ImpactModel, switching, contact, b0, b1) -> ca.SX:
    """(1 - 2 flag) s per switching function s, >= 0 where its flag no longer holds; masked
    where it cannot trigger (slip speeds out of contact, or without Ambrosio friction)."""
    out = []
    for k, pair in enumerate(model.pairs):
        s = switching[3 * k : 3 * k + 3]
        out.append((1 - 2 * contact[k]) * s[0])
        live = contact[k] if pair.friction_law.speed_events else 0
        out.append(ca.if_else(live, (1 - 2 * b0[k]) * s[1], MASKED))
        out.append(ca.if_else(live, (1 - 2 * b1[k]) * s[2], MASKED))
    return ca.vertcat(*out)


def dormand_prince(f, y, t, dt, k1):
    """(y1, the embedded error estimate) of one step from y at t, k1 = f(y, t)'s derivative."""
    stages = [k1]
    for i in range(1, 7):
        stages.append(f(y + dt * sum(a * k for a, k in zip(A[i], stages) if a), t + C[i] * dt)[0])
    y1 = y + dt * sum(b * k for b, k in zip(B, stages) if b)
    return y1, dt * sum((b - e) * k for b, e, k in zip(B, B_EMBEDDED, stages) if b != e)


def switched_flags(model: ImpactModel, commit, flip, end, contact, b0, b1, speed) -> ca.SX:
    """The flags after a step: at a located event those whose switching value crossed flip;
    a contact onset sets the slip flags from the slip speed and freezes the impact speed."""
    new_contact, new_b0, new_b1, new_speed = [], [], [], []
    slip_end, rate_end = ca.fabs(end[5]), end[4]
    for k, pair in enumerate(model.pairs):
        entering = ca.logic_and(commit, ca.logic_and(flip[3 * k], 1 - contact[k]))
        new_contact.append(ca.if_else(ca.logic_and(commit, flip[3 * k]), 1 - contact[k], contact[k]))
        new_b0.append(
            ca.if_else(
                entering, slip_end[k] > pair.v0, ca.if_else(ca.logic_and(commit, flip[3 * k + 1]), 1 - b0[k], b0[k])
            )
        )
        new_b1.append(
            ca.if_else(
                entering, slip_end[k] > pair.v1, ca.if_else(ca.logic_and(commit, flip[3 * k + 2]), 1 - b1[k], b1[k])
            )
        )
        new_speed.append(ca.if_else(entering, ca.fmax(rate_end[k], MIN_IMPACT_SPEED), speed[k]))
    return ca.vertcat(*new_contact, *new_b0, *new_b1, *new_speed)


def error_norm(y, y1, error, atol, rtol, m: int) -> ca.SX:
    """The largest error estimate of the first m entries of the state (q and v), each scaled
    by atol + rtol times the larger of its values at the step's start and end."""
    scale = atol + rtol * ca.fmax(ca.fabs(y[:m]), ca.fabs(y1[:m]))
    return ca.mmax(ca.fabs(error[:m]) / scale)


def next_step_size(h, dt, err, h_max, reject, accept) -> ca.SX:
    """The next trial step: shrunk after a rejected step, grown (at most to h_max) after an
    accepted one, kept otherwise (while locating an event)."""
    # err below ERR_FLOOR grows the step by the most (4) either way; the floor keeps its
    # derivative finite (state_sensitivity differentiates these steps)
    growth = ca.fmin(4.0, ca.fmax(0.2, 0.9 * ca.fmax(err, ERR_FLOOR) ** -0.2))
    return ca.if_else(
        reject,
        h * ca.fmax(0.1, 0.9 * ca.fmax(err, ERR_FLOOR) ** -0.2),
        ca.if_else(accept, ca.fmin(h_max, dt * growth), h),
    )


def event_step(model: ImpactModel) -> ca.Function:
    """(S, p, settings = [until, rtol, h_max, atol (2n)]) -> S': one call of the state machine."""
    n, P = model.bodies.size, len(model.pairs)
    L = EventLayout(n, P)
    rhs = rhs_function(model)
    S, p = ca.SX.sym("S", L.size), model.p
    settings = ca.SX.sym("settings", 3 + 2 * n)
    until, rtol, h_max, atol = settings[0], settings[1], settings[2], settings[3:]
    t, y, h = S[0], S[L.y], S[L.at("h")]
    contact, b0, b1, speed = (S[L.at(k)] for k in ("contact", "beyond_v0", "beyond_v1", "speed"))
    locating = S[L.at("locating")]
    h_lo, G_lo, h_hi, G_hi, side = (S[L.at(k)] for k in ("h_lo", "G_lo", "h_hi", "G_hi", "side"))

    def f(state, time):
        return rhs(state[:n], state[n : 2 * n], time, contact, b0, b1, speed, p)

    eps_t = 8 * 2.2e-16 * (ca.fabs(t) + h_hi)
    regula_falsi = h_lo - G_lo * (h_hi - h_lo) / (G_hi - G_lo)
    trial_locate = ca.if_else(h_hi - h_lo <= eps_t, h_hi, ca.fmin(ca.fmax(regula_falsi, h_lo), h_hi))
    dt = ca.if_else(locating, trial_locate, ca.fmin(h, until - t))
    first = f(y, t)
    y1, error = dormand_prince(f, y, t, dt, first[0])
    err = error_norm(y, y1, error, atol, rtol, 2 * n)
    end = f(y1, t + dt)
    viol0, viol1 = (violations(model, sw, contact, b0, b1) for sw in (first[1], end[1]))
    G0, G1 = ca.mmax(viol0), ca.mmax(viol1)
    crossed = G1 >= 0
    # free steps
    reject = ca.logic_and(1 - locating, err > 1)
    start = ca.logic_and(ca.logic_and(1 - locating, err <= 1), crossed)
    accept = ca.logic_and(ca.logic_and(ca.logic_and(1 - locating, err <= 1), 1 - crossed), dt > 0)  # 0: at the end
    # locating: the Illinois method on the step size
    new_hi = ca.if_else(crossed, dt, h_hi)
    new_lo = ca.if_else(crossed, h_lo, dt)
    commit = ca.logic_and(
        locating, ca.logic_and(crossed, ca.logic_or(new_hi - new_lo <= eps_t, G1 <= SWITCH_TOLERANCE))
    )
    G_hi_loc = ca.if_else(crossed, G1, ca.if_else(side < 0, G_hi / 2, G_hi))
    G_lo_loc = ca.if_else(crossed, ca.if_else(side > 0, G_lo / 2, G_lo), G1)
    advance = ca.logic_or(accept, commit)
    h_next = next_step_size(h, dt, err, h_max, reject, accept)
    flags = switched_flags(model, commit, viol1 >= 0, end, contact, b0, b1, speed)
    out = ca.vertcat(
        ca.if_else(advance, t + dt, t),
        ca.if_else(advance, y1, y),
        h_next,
        flags,
        ca.if_else(start, 1, ca.if_else(commit, 0, locating)),
        ca.if_else(start, 0, ca.if_else(locating, new_lo, h_lo)),
        ca.if_else(start, G0, ca.if_else(locating, G_lo_loc, G_lo)),
        ca.if_else(start, dt, ca.if_else(locating, new_hi, h_hi)),
        ca.if_else(start, G1, ca.if_else(locating, G_hi_loc, G_hi)),
        ca.if_else(start, 1, ca.if_else(locating, ca.if_else(crossed, 1, -1), side)),
        advance,
        commit,
    )
    return ca.Function("event_step", [S, p, settings], [out], ["S", "p", "settings"], ["S1"])
