"""Radau IIA collocation (three stages, classical order 5; Hairer and Wanner 1996, Sec. IV.5
and VII.4) of the dynamics form's DAE (models.graph.dynamics)

    x' = v - G^T mu,   R(x, v, a, lam, p(t), pdot(t), pddot(t)) = 0,
    g(x, p(t)) = 0,    G v + g_p pdot = 0,

in the stabilized index-2 form of Gear, Gupta and Leimkuhler (mu is zero in the exact solution
and keeps the positions on g = 0 and the velocities on its rate). Newton's unknowns are the
stages' accelerations A_j, multipliers L_j and mu_j, and positions X_j:

    V_i = v_n + h sum_j a_ij A_j,   X_i = x_n + h sum_j a_ij (V_j - G_j^T mu_j),

and the scheme is stiffly accurate: the step ends at the last stage (c_3 = 1). The position
rows are divided by h, the constraints by h^2 and their rates by h, which keeps Newton's matrix
well conditioned as h shrinks.

Measured (tests/dynamics/test_radau.py): on the rod of examples/rod_free_vibration.json released
smoothly, its tip history agrees with the shipped generalized-alpha at 0.25 ms steps to 1e-5,
and its error falls as h^3.3-3.7, not h^5: the stiff axial and shear modes follow the load
quasi-statically, and on them Radau IIA keeps its stage order 3 (order reduction of stiff
problems). This module is the scheme on the dense form, one CasADi rootfinder per step
(8 ms a step at 2 intervals, 120-250 ms at 8): the reference for the accuracy the element
kernels' stepping is to reach (issue 50), not yet a scheme of `simulate`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from flexmech.models.graph.structure import Structure
from flexmech.service.dynamics.histories import Histories, no_histories
from flexmech.service.dynamics.modes import form_of

SQRT6 = math.sqrt(6.0)
NODES = np.array([(4 - SQRT6) / 10, (4 + SQRT6) / 10, 1.0])  # c
COEFFICIENTS = np.array(  # a_ij
    [
        [(88 - 7 * SQRT6) / 360, (296 - 169 * SQRT6) / 1800, (-2 + 3 * SQRT6) / 225],
        [(296 + 169 * SQRT6) / 1800, (88 + 7 * SQRT6) / 360, (-2 - 3 * SQRT6) / 225],
        [(16 - SQRT6) / 36, (16 + SQRT6) / 36, 1 / 9],
    ]
)
STAGES = 3
NEWTON_TOLERANCE = 1e-11  # of the residual rows (forces in the form's units, constraints over h^2)
MAX_NEWTON = 30


@dataclass
class RadauRun:
    times: list[float] = field(default_factory=list)
    positions: list[np.ndarray] = field(default_factory=list)
    velocities: list[np.ndarray] = field(default_factory=list)
    status: str = "finished"
    message: str = ""
    steps: int = 0
    seconds: float = 0.0


class RadauStepper:
    """Steps of one structure under its histories (loads and prescribed motions in time)."""

    def __init__(self, structure: Structure, p: np.ndarray, histories: Histories | None = None, damping: float = 0.0):
        self.histories = histories or no_histories()
        self.p = np.asarray(p, dtype=float)
        form = form_of(structure, tuple(self.histories.moving))
        self.n, self.m = len(form.unknowns), form.n_equalities
        self.unknowns = form.unknowns
        self._step = self._build(form, len(self.p), len(self.histories.moving), damping)
        self._guess = np.zeros(STAGES * (2 * self.n + 2 * self.m))

    def _build(self, form, n_p: int, k: int, damping: float) -> ca.Function:
        n, m = self.n, self.m
        x0, v0, h = ca.SX.sym("x0", n), ca.SX.sym("v0", n), ca.SX.sym("h")
        P, Pd, Pdd = ca.SX.sym("P", n_p, STAGES), ca.SX.sym("Pd", k, STAGES), ca.SX.sym("Pdd", k, STAGES)
        A, L, U = ca.SX.sym("A", n, STAGES), ca.SX.sym("L", m, STAGES), ca.SX.sym("U", m, STAGES)
        a = ca.DM(COEFFICIENTS)
        V = ca.repmat(v0, 1, STAGES) + h * ca.mtimes(A, a.T)
        # GGL: x' = v - G^T mu keeps x on g = 0 and v on G v + g_p pdot = 0, an index-2 system on
        # which positions and velocities both reach order 2s - 1 where the problem is not stiff
        # (mu is zero in the exact solution; the stiff rod keeps order 3-4: module docstring)
        xs, p_sym = ca.SX.sym("xs", n), ca.SX.sym("ps", n_p)
        g_of = form.constraints(xs, p_sym)
        G_of = ca.Function("G", [xs, p_sym], [ca.jacobian(g_of, xs)])
        gp_of = ca.Function("gp", [xs, p_sym], [ca.jacobian(g_of, p_sym)])
        X = ca.SX.sym("X", n, STAGES)  # the stage positions are unknowns too (they depend on mu)
        rows = []
        drift = ca.horzcat(*[V[:, j] - ca.mtimes(G_of(X[:, j], P[:, j]).T, U[:, j]) for j in range(STAGES)])
        for i in range(STAGES):
            rows.append((X[:, i] - x0 - h * ca.mtimes(drift, a[i, :].T)) / h)
        for i in range(STAGES):
            Gi = G_of(X[:, i], P[:, i])
            rate = ca.DM.zeros(n_p, 1) if k == 0 else ca.SX.zeros(n_p, 1)
            for slot, index in enumerate(self.histories.moving):
                rate[index] = Pd[slot, i]
            rows.append(form.equations(X[:, i], V[:, i], A[:, i], L[:, i], P[:, i], Pd[:, i], Pdd[:, i], damping))
            rows.append(form.constraints(X[:, i], P[:, i]) / h**2)
            rows.append((ca.mtimes(Gi, V[:, i]) + ca.mtimes(gp_of(X[:, i], P[:, i]), rate)) / h)
        unknowns = ca.vertcat(ca.vec(A), ca.vec(L), ca.vec(U), ca.vec(X))
        parameters = ca.vertcat(x0, v0, h, ca.vec(P), ca.vec(Pd), ca.vec(Pdd))
        residual = ca.Function("radau_residual", [unknowns, parameters], [ca.vertcat(*rows)])
        solve = ca.rootfinder(
            "radau_stages",
            "newton",
            residual,
            {"abstol": NEWTON_TOLERANCE, "max_iter": MAX_NEWTON, "error_on_fail": False},
        )
        w0, q = ca.MX.sym("w0", unknowns.numel()), ca.MX.sym("q", parameters.numel())
        w = solve(w0, q)
        rest = ca.Function("radau_rest", [unknowns, parameters], [X[:, -1], V[:, -1], ca.norm_inf(ca.vertcat(*rows))])
        x_end, v_end, left = rest(w, q)
        return ca.Function("radau_step", [w0, q], [w, x_end, v_end, left])

    def step(self, t: float, x: np.ndarray, v: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, float]:
        """(x, v) at t + h, and the largest residual row left (NEWTON_TOLERANCE when settled)."""
        times = t + h * NODES
        P, Pd, Pdd = self.histories.at_times(self.p, times)
        q = np.concatenate([x, v, [h], P.ravel(order="F"), Pd.ravel(order="F"), Pdd.ravel(order="F")])
        guess = self._guess.copy()
        guess[-STAGES * self.n :] = np.tile(x, STAGES)  # the stage positions start at x
        w, x_end, v_end, left = self._step(guess, q)
        self._guess = np.asarray(w, dtype=float).ravel()
        return np.asarray(x_end, dtype=float).ravel(), np.asarray(v_end, dtype=float).ravel(), float(left)

    def run(self, x0: np.ndarray, v0: np.ndarray, until: float, h: float) -> RadauRun:
        """Fixed steps h from t = 0 to `until` (the last step shortened to land on it)."""
        started = time.perf_counter()
        run = RadauRun()
        t, x, v = 0.0, np.asarray(x0, dtype=float), np.asarray(v0, dtype=float)
        run.times.append(t), run.positions.append(x), run.velocities.append(v)
        while t < until * (1 - 1e-12):
            step = min(h, until - t)
            x, v, left = self.step(t, x, v, step)
            if not np.isfinite(left) or left > 1e3 * NEWTON_TOLERANCE:
                run.status, run.message = "failed", f"Newton did not settle the stages at t = {t:g} s ({left:.2e} left)"
                break
            t += step
            run.steps += 1
            run.times.append(t), run.positions.append(x), run.velocities.append(v)
        run.seconds = time.perf_counter() - started
        return run
