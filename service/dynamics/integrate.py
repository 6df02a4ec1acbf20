"""Time integration of the dynamics form: each step solves for the accelerations and the
constraint forces at the step's end by Newton with the exact Jacobian (one CasADi Function
per structure and scheme), the constraints held at position level (scaled by 1 / (beta h^2)).
Loads and motions take their values at the step's end from the histories.

Every step also measures the energies: kinetic T, the potential V_held without the varying
loads, the power of the inputs (varying loads and prescribed motions) and of the damping,
integrated by the trapezoidal rule into works, so that the balance
T + V_held - W_inputs + W_damping stays at its start (its drift is the `balance` history).
A step that does not converge ends the run with its status and the history so far."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from models.dynamics import DynamicsForm
from models.structure import Structure
from service.dynamics.functions import form_of, monitor_function, step_function
from service.dynamics.histories import Histories, no_histories
from service.dynamics.schemes import Scheme
from service.dynamics.window import CONSTRAINT_TOLERANCE, MAX_NEWTON, NEWTON_TOLERANCE, WINDOW, window_function

WINDOW_ACCEPTANCE = 10 * NEWTON_TOLERANCE  # a window's step whose Newton stopped on a tiny step


@dataclass
class History:
    status: str  # finished | not_converged | stopped
    message: str
    times: list[float] = field(default_factory=list)
    x: list[np.ndarray] = field(default_factory=list)
    v: list[np.ndarray] = field(default_factory=list)
    acceleration: list[np.ndarray] = field(default_factory=list)
    lam: list[np.ndarray] = field(default_factory=list)
    p: list[np.ndarray] = field(default_factory=list)
    motion_forces: list[np.ndarray] = field(default_factory=list)  # each prescribed motion's reaction
    kinetic: list[float] = field(default_factory=list)
    potential: list[float] = field(default_factory=list)  # strain and gravity: without the varying loads
    input_work: list[float] = field(default_factory=list)
    damping_work: list[float] = field(default_factory=list)
    newton_iterations: int = 0
    steps: int = 0
    seconds: float = 0.0

    @property
    def balance(self) -> np.ndarray:
        """T + V - W_inputs + W_damping, less its start."""
        total = (np.array(self.kinetic) + np.array(self.potential) - np.array(self.input_work)
                 + np.array(self.damping_work))
        return total - total[0]

    def balance_error(self) -> float:
        """The largest |balance| relative to the largest energy the run saw."""
        size = max(np.abs(self.kinetic).max(), np.abs(np.array(self.potential) - self.potential[0]).max(),
                   np.abs(self.input_work).max(), 1e-300)
        return float(np.abs(self.balance).max() / size)


def consistent_acceleration(form: DynamicsForm, x, v, p, pdot, pddot, damping: float) -> tuple[np.ndarray, np.ndarray]:
    """(qdd, lam) that satisfy the equations and the constraints' second derivative at (x, v)."""
    n, m = len(form.unknowns), form.n_equalities
    M = np.asarray(form.mass(x, p), dtype=float)
    rest = np.asarray(form.equations(x, v, np.zeros(n), np.zeros(m), p, pdot, pddot, damping), dtype=float).ravel()
    G = np.asarray(form.constraint_jacobian(x, p), dtype=float).reshape(m, n)
    drift = np.asarray(form.constraint_drift(x, v, p, pdot, pddot), dtype=float).ravel()
    K = np.block([[M, G.T], [G, np.zeros((m, m))]])
    solution = np.linalg.solve(K, np.concatenate([-rest, -drift]))
    return solution[:n], solution[n:]


def integrate(structure: Structure, p: np.ndarray, x0: np.ndarray, v0: np.ndarray, until: float, h: float,
              scheme: Scheme, damping: float = 0.0, every: int = 1, stop=None, histories: Histories | None = None,
              progress=None, compiled: bool = False) -> History:
    """States from t = 0 to `until` in steps h (seconds), keeping every `every`-th.
    Steps run in windows (service.dynamics.window; `compiled`: as a C library); a step the
    window's Newton does not settle is retried by Newton in Python before the run stops.
    `stop()` true ends the run early; `progress(t)` hears after every window."""
    started = time.perf_counter()
    histories = histories or no_histories()
    moving = histories.moving
    form = form_of(structure, moving)
    window = window_function(structure, scheme, moving, WINDOW, compiled)
    mask = histories.load_mask(len(p))
    n = len(form.unknowns)
    x, v = np.asarray(x0, dtype=float).copy(), np.asarray(v0, dtype=float).copy()
    p_now, pdot, pddot = histories.at(p, 0.0)
    qdd, lam = consistent_acceleration(form, x, v, p_now, pdot, pddot, damping)
    state = np.concatenate([x, v, qdd, qdd, lam])
    history = History("finished", "")
    measured = _measure(monitor_function(structure, moving), state, n, p_now, pdot, pddot, mask, damping)
    works = np.zeros(2)
    _keep(history, 0.0, state, n, p_now, measured, works)
    steps, k = int(round(until / h)), 0
    while k < steps:
        if stop is not None and stop():
            history.status, history.message = "stopped", f"stopped at t = {k * h:g} s"
            break
        inputs = [histories.at(p, (k + j) * h) for j in range(1, WINDOW + 1)]
        P, PD, PDD = (np.column_stack([q[i] for q in inputs]) if len(inputs[0][i]) else np.zeros((0, WINDOW))
                      for i in range(3))
        S, monitors, residuals = (np.asarray(q, dtype=float) for q in window(state, h, P, PD, PDD, damping, mask))
        settled = np.flatnonzero(~(residuals.ravel() <= WINDOW_ACCEPTANCE))  # NaN too
        good = min(settled[0] if len(settled) else WINDOW, steps - k)
        for j in range(good):
            now = _monitored(monitors[:, j])
            works += 0.5 * h * (np.array(now[2:4]) + np.array(measured[2:4]))
            measured, k = now, k + 1
            if k % every == 0 or k == steps:
                _keep(history, k * h, S[:, j], n, P[:, j], measured, works)
        if good:
            state = S[:, good - 1].copy()
        if k < steps and good < WINDOW:  # the window's Newton did not settle step k + 1: Newton in Python
            state, F = _python_step(structure, scheme, moving, state, n, h, inputs[good], damping)
            history.newton_iterations += 1
            if state is None:
                history.status = "not_converged"
                history.message = (f"the step from t = {k * h:g} s to {(k + 1) * h:g} s did not converge in "
                                   f"{MAX_NEWTON} Newton iterations (residual {F:.3g}): try a smaller step")
                break
            now = _measure(monitor_function(structure, moving), state, n, *inputs[good], mask, damping)
            works += 0.5 * h * (np.array(now[2:4]) + np.array(measured[2:4]))
            measured, k = now, k + 1
            if k % every == 0 or k == steps:
                _keep(history, k * h, state, n, inputs[good][0], measured, works)
        history.steps = k
        if progress is not None:
            progress(k * h)
    history.seconds = time.perf_counter() - started
    return history


def _python_step(structure, scheme, moving, state, n, h, inputs, damping):
    """One step by Newton in Python from `state`: (new state, residual) or (None, residual)."""
    p1, pdot1, pddot1 = inputs
    step = step_function(structure, scheme, moving)
    x, v, a, qdd, lam = state[:n], state[n:2 * n], state[2 * n:3 * n], state[3 * n:4 * n], state[4 * n:]
    u = np.concatenate([qdd, lam])
    for _ in range(MAX_NEWTON):
        F, J, x1, v1, a1 = step(u, x, v, a, qdd, h, p1, pdot1, pddot1, damping)
        F = np.asarray(F, dtype=float).ravel()
        if not np.all(np.isfinite(F)):
            break
        if (np.abs(F[:n]).max(initial=0.0) <= NEWTON_TOLERANCE
                and np.abs(F[n:]).max(initial=0.0) * scheme.beta * h**2 <= CONSTRAINT_TOLERANCE):
            return np.concatenate([np.asarray(q, dtype=float).ravel() for q in (x1, v1, a1)] + [u]), 0.0
        u = u - np.linalg.solve(np.asarray(J, dtype=float), F)
    return None, float(np.abs(F[:n]).max(initial=np.inf)) if np.all(np.isfinite(F)) else float("nan")


def _measure(monitor, state, n, p, pdot, pddot, mask, damping) -> tuple:
    x, v, qdd, lam = state[:n], state[n:2 * n], state[3 * n:4 * n], state[4 * n:]
    return _monitored(np.concatenate([np.asarray(q, dtype=float).ravel()
                                      for q in monitor(x, v, qdd, lam, p, pdot, pddot, mask, damping)]))


def _monitored(column: np.ndarray) -> tuple:
    """(T, V_held, input power, damping power, motion forces) of a monitor column."""
    return float(column[0]), float(column[1]), float(column[2]), float(column[3]), np.array(column[4:])


def _keep(history: History, t, state, n, p, measured, works) -> None:
    history.times.append(t)
    history.x.append(state[:n].copy())
    history.v.append(state[n:2 * n].copy())
    history.acceleration.append(state[3 * n:4 * n].copy())
    history.lam.append(state[4 * n:].copy())
    history.p.append(np.array(p, dtype=float))
    history.motion_forces.append(measured[4])
    history.kinetic.append(measured[0])
    history.potential.append(measured[1])
    history.input_work.append(float(works[0]))
    history.damping_work.append(float(works[1]))
