"""Stepping the dynamics form: each step solves for the accelerations and the
constraint forces at the step's end by Newton with the exact Jacobian (one CasADi Function
per structure and scheme), the constraints held at position level (scaled by 1 / (beta h^2)).
Loads and motions take their values at the step's end from the histories.

Every step also measures the energies: kinetic T, the potential V_held without the varying
loads, the power of the inputs (varying loads and prescribed motions) and of the damping,
integrated by the trapezoidal rule into works, so that the balance
T + V_held - W_inputs + W_damping stays at its start (service.dynamics.run reports its drift).
A step that does not converge ends the run with its status and the history so far."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import null_space

from models import MechanismError
from models.dynamics import DynamicsForm
from models.structure import Structure
from service.dynamics.functions import form_of, monitor_function, step_function
from service.dynamics.histories import Histories
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
    newton_iterations: int = 0  # steps retried by Newton in Python
    steps: int = 0
    seconds: float = 0.0
    resume: "Resume | None" = None


def consistent_acceleration(form: DynamicsForm, x, v, p, pdot, pddot, damping: float) -> tuple[np.ndarray, np.ndarray]:
    """(qdd, lam) that satisfy the equations and the constraints' second derivative at (x, v)."""
    n, m = len(form.unknowns), form.n_equalities
    M = np.asarray(form.mass(x, p), dtype=float)
    rest = np.asarray(form.equations(x, v, np.zeros(n), np.zeros(m), p, pdot, pddot, damping), dtype=float).ravel()
    G = np.asarray(form.constraint_jacobian(x, p), dtype=float).reshape(m, n)
    drift = np.asarray(form.constraint_drift(x, v, p, pdot, pddot), dtype=float).ravel()
    K = np.block([[M, G.T], [G, np.zeros((m, m))]])
    if np.linalg.cond(K) > 1e14:
        loose = np.abs(null_space(K, rcond=1e-12)[:n]).max(axis=1, initial=0.0)  # what moves undetermined
        massless = [form.unknowns[i] for i in range(n) if loose[i] > 0.1 * loose.max()]
        raise MechanismError("/bodies", "the motion is undetermined: a coordinate that is free carries no mass"
                             + (f" ({', '.join(massless[:6])})" if massless else "")
                             + ": give the body a mass (and an inertia, for its angle), or tie the coordinate by a "
                             "joint or a link")
    solution = np.linalg.solve(K, np.concatenate([-rest, -drift]))
    return solution[:n], solution[n:]


@dataclass
class Resume:
    """Where a run stands after step `step`: enough to go on exactly as if never stopped."""

    step: int
    state: np.ndarray  # [x; v; a; qdd; lam]
    works: np.ndarray  # (inputs, damping)
    monitor: np.ndarray  # the last step's monitor column
    time: float = 0.0  # seconds
    h: float | None = None  # adaptive steps: the next step to try

    def to_json(self) -> dict:
        return {"step": self.step, "state": self.state.tolist(), "works": self.works.tolist(),
                "monitor": self.monitor.tolist(), "time": self.time, "h": self.h}

    @classmethod
    def from_json(cls, data: dict) -> "Resume":
        return cls(int(data["step"]), *(np.array(data[k], dtype=float) for k in ("state", "works", "monitor")),
                   float(data.get("time", 0.0)), data.get("h"))


def start_of(structure: Structure, p, x0, v0, histories: Histories, damping: float) -> Resume:
    """The run's state at t = 0: (x0, v0) with consistent accelerations."""
    moving = histories.moving
    form = form_of(structure, moving)
    n = len(form.unknowns)
    x, v = np.asarray(x0, dtype=float).copy(), np.asarray(v0, dtype=float).copy()
    p_now, pdot, pddot = histories.at(p, 0.0)
    qdd, lam = consistent_acceleration(form, x, v, p_now, pdot, pddot, damping)
    state = np.concatenate([x, v, qdd, qdd, lam])
    monitor = _monitor_column(monitor_function(structure, moving), state, n, p_now, pdot, pddot,
                              histories.load_mask(len(p)), damping)
    return Resume(0, state, np.zeros(2), monitor)


class StepRunner:
    """The Functions and inputs of one run in fixed steps; window() advances by up to WINDOW."""

    def __init__(self, structure, p, h, scheme, damping, histories: Histories, compiled: bool, until: float,
                 every: int):
        self.structure, self.p, self.h, self.scheme, self.damping, self.histories = (
            structure, p, h, scheme, damping, histories)
        self.until, self.every, self.steps = until, every, int(round(until / h))
        self.moving = histories.moving
        self.n = len(form_of(structure, self.moving).unknowns)
        self.function = window_function(structure, scheme, self.moving, WINDOW, compiled)
        self.mask = histories.load_mask(len(p))

    def done(self, at: Resume) -> bool:
        return at.step >= self.steps

    def keep(self, history: History, at: Resume, p: np.ndarray | None = None) -> None:
        p = self.histories.at(self.p, at.time)[0] if p is None else p
        _keep(history, at.time, at.state, self.n, p, _monitored(at.monitor), at.works)

    def run_window(self, at: Resume, h: float):
        """The window's inputs (columns P, PD, PDD), states, monitors and how many steps settled."""
        P, PD, PDD = self.histories.at_times(self.p, at.time + h * np.arange(1, WINDOW + 1))
        try:
            S, monitors, residuals = (np.asarray(q, dtype=float)
                                      for q in self.function(at.state, h, P, PD, PDD, self.damping, self.mask))
        except RuntimeError:  # a factorization met a singular or non-finite Jacobian: no step of it counts
            return (P, PD, PDD), None, None, 0
        unsettled = np.flatnonzero(~(residuals.ravel() <= WINDOW_ACCEPTANCE))  # NaN too
        return (P, PD, PDD), S, monitors, unsettled[0] if len(unsettled) else WINDOW

    def window(self, history: History, at: Resume) -> Resume:
        inputs, S, monitors, settled = self.run_window(at, self.h)
        good = min(settled, self.steps - at.step)
        at = self.accept(history, at, S, monitors, inputs[0], good, self.h)
        if not self.done(at) and good < WINDOW:  # the window's Newton did not settle this step: Newton in Python
            step_inputs = tuple(q[:, good] for q in inputs)
            state, residual = _python_step(self.structure, self.scheme, self.moving, at.state, self.n, self.h,
                                           step_inputs, self.damping)
            history.newton_iterations += 1
            if state is None:
                history.status = "not_converged"
                history.message = (f"the step from t = {at.time:g} s to {at.time + self.h:g} s did not converge "
                                   f"in {MAX_NEWTON} Newton iterations (residual {residual:.3g}): try a smaller step")
                return at
            monitor = _monitor_column(monitor_function(self.structure, self.moving), state, self.n, *step_inputs,
                                      self.mask, self.damping)
            at = self.advance(history, at, state, monitor, self.h, p=step_inputs[0])
        return at

    def accept(self, history, at: Resume, S, monitors, P, count: int, h: float, final: bool = False) -> Resume:
        """The window's first `count` steps (in steps h): works summed, every `every`-th kept."""
        if count == 0:
            return at
        previous = np.column_stack([at.monitor, monitors[:, :count - 1]])
        works = at.works[:, None] + np.cumsum(0.5 * h * (monitors[2:4, :count] + previous[2:4]), axis=1)
        start = at
        for j in range(count):
            step, last = start.step + j + 1, j == count - 1
            now = self.time_of(step, start, h * (j + 1))
            kept = step % self.every == 0 or (last and final) or now >= self.until * (1 - 1e-12)
            if kept or last:
                at = Resume(step, S[:, j].copy(), works[:, j], monitors[:, j].copy(), now, start.h)
            if kept:
                self.keep(history, at, P[:, j])
        return at

    def advance(self, history, at: Resume, state, monitor, h: float, final: bool = False, p=None) -> Resume:
        works = at.works + 0.5 * h * (monitor[2:4] + at.monitor[2:4])
        step = at.step + 1
        now = Resume(step, np.array(state), works, np.array(monitor), self.time_of(step, at, h), at.h)
        if now.step % self.every == 0 or final or self.done(now):
            self.keep(history, now, p)
        return now

    def time_of(self, step: int, at: Resume, h: float) -> float:
        return step * self.h  # fixed steps: no sum of rounding errors


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


def _monitor_column(monitor, state, n, p, pdot, pddot, mask, damping) -> np.ndarray:
    x, v, qdd, lam = state[:n], state[n:2 * n], state[3 * n:4 * n], state[4 * n:]
    return np.concatenate([np.asarray(q, dtype=float).ravel()
                           for q in monitor(x, v, qdd, lam, p, pdot, pddot, mask, damping)])


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
