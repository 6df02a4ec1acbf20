"""Stepping the dynamics form on element kernels (service.dynamics.engine): each step solves for
the accelerations and the constraint forces at the step's end by Newton, the constraints held
at position level; loads and motions take their values at the step's end from the histories.
A step that enters a damped contact is replaced by a step onto its onset and one over the rest
(service.dynamics.onsets), so a fixed-step run's states are on its grid but for those onsets.

Every step also measures the energies: kinetic T, the potential V_held without the varying
loads, the power of the inputs (varying loads and prescribed motions) and of the damping,
integrated by the trapezoidal rule into works, so that the balance
T + V_held - W_inputs + W_damping stays at its start (service.dynamics.run reports its drift).
A step that does not converge ends the run with its status and the history so far."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from flexmech.models import MechanismError
from flexmech.models.graph.structure import Structure
from flexmech.models.kernels.layout import layout_of
from flexmech.service.buffered import BufferedCall
from flexmech.service.dynamics.engine import WINDOW_ACCEPTANCE, Engine, engine_for, stages_of
from flexmech.service.dynamics.histories import Histories
from flexmech.service.dynamics.onsets import Onsets, crossing, step_onto_onset
from flexmech.service.kernels import compiled_for
from flexmech.service.kernels.cache import is_compiled
from flexmech.service.kernels.queue import request_chain

WINDOW = 20  # steps per call


@dataclass
class History:
    status: str  # finished | not_converged | stopped | step_limit
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
    friction_work: list[float] = field(default_factory=list)  # of the contacts' friction (<= 0)
    contact_damping_work: list[float] = field(default_factory=list)  # of the contacts' damping (<= 0)
    newton_iterations: int = 0  # steps rescued by full Newton
    iterations: int = 0  # Newton iterations in all
    steps: int = 0
    seconds: float = 0.0
    resume: Resume | None = None
    kernels: str = ""  # how its windows ran (service.dynamics.engine.Engine.kernels)


@dataclass
class Resume:
    """Where a run stands after step `step`: enough to go on exactly as if never stopped."""

    step: int
    state: np.ndarray  # [x; v; a; qdd; lam]
    works: np.ndarray  # (inputs, damping, contacts' friction, contacts' damping)
    monitor: np.ndarray  # the last step's monitor column
    time: float = 0.0  # seconds
    h: float | None = None  # adaptive steps: the next step to try
    inserted: int = 0  # steps added at located contact onsets (service.dynamics.onsets)
    onset_speeds: list[float] | None = None  # per damped contact pair, its approach speed at its last onset

    def to_json(self) -> dict:
        return {
            "step": self.step,
            "state": self.state.tolist(),
            "works": self.works.tolist(),
            "monitor": self.monitor.tolist(),
            "time": self.time,
            "h": self.h,
            "inserted": self.inserted,
            "onset_speeds": self.onset_speeds,
        }

    @classmethod
    def from_json(cls, data: dict) -> Resume:
        state, works, monitor = (np.array(data[k], dtype=float) for k in ("state", "works", "monitor"))
        if len(works) == 2:  # stored before the contacts' friction and damping had rows: none acted
            works, monitor = np.append(works, [0.0, 0.0]), np.insert(monitor, 4, [0.0, 0.0])
        return cls(
            int(data["step"]),
            state,
            works,
            monitor,
            float(data.get("time", 0.0)),
            data.get("h"),
            int(data.get("inserted", 0)),
            data.get("onset_speeds"),
        )


def window_length(scheme, steps: int) -> int:
    """Steps per window Function: `steps`, divided by a stage scheme's stages, so that a window
    holds as many implicit solves (and as much generated glue, service.kernels.windows) as a
    window of generalized-alpha steps."""
    return max(1, steps // stages_of(scheme))


def engine_of(structure: Structure, scheme, histories: Histories) -> Engine:
    """The structure's engine, on the compiled kernels the cache has; the others run
    interpreted, and a server's build queue is asked for them (service.kernels.queue)."""
    signatures = [g.signature for g in layout_of(structure).groups]
    compiled = compiled_for(signatures)
    for signature in signatures:
        if signature not in compiled or not is_compiled(signature):  # missing, or loaded but evicted since
            request_chain(signature)
    return engine_for(structure, scheme, histories.moving, compiled)


def start_of(structure: Structure, p, x0, v0, histories: Histories, damping: float, scheme=None) -> Resume:
    """The run's state at t = 0: (x0, v0) with consistent accelerations."""
    from flexmech.service.dynamics.schemes import newmark

    engine = engine_of(structure, scheme or newmark(), histories)
    x, v = np.asarray(x0, dtype=float).copy(), np.asarray(v0, dtype=float).copy()
    p_now, pdot, pddot = histories.at(p, 0.0)
    mask = histories.load_mask(len(p))
    data = engine.data(p_now)
    try:
        qdd, lam, norm, monitor = (
            np.asarray(q, dtype=float).ravel() for q in engine.start(x, v, p_now, pdot, pddot, damping, mask, *data)
        )
    except RuntimeError:  # a zero pivot: the system of accelerations is singular
        qdd, norm = np.array([np.nan]), np.array([np.nan])
    if not (np.all(np.isfinite(qdd)) and float(norm[0]) <= 1e-6 * max(1.0, np.abs(qdd).max())):
        massless = massless_coordinates(structure, x, p_now)
        raise MechanismError(
            "/bodies",
            "the motion is undetermined: a coordinate that is free carries no mass"
            + (f" ({', '.join(massless[:6])})" if massless else " (or the start is inconsistent)")
            + ": give the body a mass (and an inertia, for its angle), or tie the coordinate by a "
            "joint or a link",
        )
    state = np.concatenate([x, v, qdd, qdd, lam])
    return Resume(0, state, np.zeros(4), monitor)


def massless_coordinates(structure: Structure, x: np.ndarray, p: np.ndarray) -> list[str]:
    """The coordinates that move in the null space of [M G'; G 0] at x: free and without mass
    (a diagnosis on the dense form, only for a start that failed)."""
    from scipy.linalg import null_space

    from flexmech.service.dynamics.modes import form_of

    form = form_of(structure)
    n, m = len(form.unknowns), form.n_equalities
    M = np.asarray(form.mass(x, p), dtype=float)
    G = np.asarray(form.constraint_jacobian(x, p), dtype=float).reshape(m, n)
    loose = np.abs(null_space(np.block([[M, G.T], [G, np.zeros((m, m))]]), rcond=1e-12)[:n]).max(axis=1, initial=0.0)
    return [form.unknowns[i] for i in range(n) if loose.max() > 0 and loose[i] > 0.1 * loose.max()]


class StepRunner:
    """The Functions and inputs of one run in fixed steps; window() advances by up to WINDOW."""

    window_steps = WINDOW  # the length of the window Function

    def __init__(self, structure, p, h, scheme, damping, histories: Histories, until: float, every: int):
        self.structure, self.p, self.h, self.scheme, self.damping, self.histories = (
            structure,
            p,
            h,
            scheme,
            damping,
            histories,
        )
        self.until, self.every, self.steps = until, every, int(round(until / h))
        self.engine = engine_of(structure, scheme, histories)
        self.stages = stages_of(scheme)  # columns of loads and motions per step
        self.window_steps = window_length(scheme, type(self).window_steps)
        self.n = self.engine.n_x
        self.mask = histories.load_mask(len(p))
        self.data = self.engine.data(histories.at(p, 0.0)[0])
        self._buffered: BufferedCall | None = None
        self.onsets = Onsets(structure, histories.moving)

    def column_times(self, start: float, h: float, size: int, steps: int) -> np.ndarray:
        """The times of a window's columns of loads and motions: each step's end or, for a stage
        scheme, its stages; the columns after the first `steps` repeat the last step's."""
        if self.stages == 1:
            return start + h * np.minimum(np.arange(1, size + 1), steps)
        step = np.minimum(np.arange(size), steps - 1)
        return (start + h * (step[:, None] + np.asarray(self.scheme.nodes)[None, :])).ravel()

    def step_columns(self, q: np.ndarray, j: int) -> np.ndarray:
        """Step j's columns of a window's loads or motions."""
        return q[:, j] if self.stages == 1 else q[:, j * self.stages : (j + 1) * self.stages]

    def end_column(self, q: np.ndarray, j: int) -> np.ndarray:
        """Step j's loads or motions at its end."""
        return q[:, j * self.stages + self.stages - 1]

    def work_increments(self, previous: np.ndarray, monitors: np.ndarray, h: float) -> np.ndarray:
        """The works of steps h (columns) from their monitors' powers: the trapezoidal rule on the
        powers at the steps' ends, or h times a stage scheme's mean power over the step
        (service.dynamics.stage_window)."""
        if self.stages == 1:
            return 0.5 * h * (monitors[2:6] + previous[2:6])
        return h * monitors[2:6]

    def done(self, at: Resume) -> bool:
        return at.step - at.inserted >= self.steps

    def speeds(self, at: Resume) -> list[float]:
        """The damped contact pairs' onset speeds (service.dynamics.onsets) as `at` has them."""
        return at.onset_speeds if at.onset_speeds is not None else [1.0] * len(self.onsets.names)

    def indentations_at(self, at: Resume) -> np.ndarray:
        """The damped contact pairs' indentations at `at`."""
        p, pdot, _ = self.histories.at(self.p, at.time)
        P = self.onsets.apply(np.asarray(p, dtype=float)[:, None], self.speeds(at))
        return self.onsets.indentations(at.state[:, None], self.n, P, np.asarray(pdot, dtype=float)[:, None])[0][:, 0]

    def keep(self, history: History, at: Resume, p: np.ndarray | None = None) -> None:
        p = self.histories.at(self.p, at.time)[0] if p is None else p
        _keep(history, at.time, at.state, self.n, p, at.monitor, at.works)

    def run_window(self, at: Resume, h: float, steps: int):
        """The window's inputs (columns P, PD, PDD), states, monitors, iterations and how many
        steps settled, for its first `steps` steps."""
        size = self.window_steps
        P, PD, PDD = self.histories.at_times(self.p, self.column_times(at.time, h, size, steps))
        if self.onsets:
            P = self.onsets.apply(P, self.speeds(at))
        try:
            S, monitors, norms, iterations = self._call(self.engine.window(size))(
                at.state, h, P, PD, PDD, self.damping, self.mask, steps, *self.data
            )
        except RuntimeError:  # a factorization met a singular or non-finite system: no step of it counts
            return (P, PD, PDD), None, None, np.zeros(steps), 0
        unsettled = np.flatnonzero(~(norms.ravel()[:steps] <= WINDOW_ACCEPTANCE))  # NaN too
        return (P, PD, PDD), S, monitors, iterations.ravel(), unsettled[0] if len(unsettled) else steps

    def _call(self, window):
        """The window called on buffers of its own (service.dynamics.buffered); a new one when the
        engine hands another window (its compiled library has arrived)."""
        if self._buffered is None or self._buffered.fn is not window:
            self._buffered = BufferedCall(window)
        return self._buffered

    def window(self, history: History, at: Resume) -> Resume:
        steps = min(self.window_steps, self.steps - (at.step - at.inserted))
        inputs, S, monitors, iterations, settled = self.run_window(at, self.h, steps)
        entering = crossing(self, at, inputs, S, settled)
        if entering is not None:  # a damped contact begins within that step: step onto its onset
            settled = entering[0]
        history.iterations += int(iterations[:settled].sum())
        at = self.accept(history, at, S, monitors, inputs[0], settled, self.h)
        if entering is not None:
            return step_onto_onset(self, history, at, entering[1], entering[2], self.h)
        if not self.done(at) and settled < steps:  # the window's factors did not settle this step: full Newton
            step_inputs = tuple(self.step_columns(q, settled) for q in inputs)
            state, monitor, norm = self.rescue(at, step_inputs, self.h)
            history.newton_iterations += 1
            # a step that enters a damped contact (whose last onset's speed made it hard): onto the onset,
            # judged by the full Newton state, or else by the window's last iterate
            judged = state if norm <= WINDOW_ACCEPTANCE else (S[:, settled] if S is not None else np.full(1, np.nan))
            entering = crossing(self, at, step_inputs, judged[:, None], 1) if np.all(np.isfinite(judged)) else None
            if entering is not None:
                return step_onto_onset(self, history, at, entering[1], entering[2], self.h)
            if not norm <= WINDOW_ACCEPTANCE:
                history.status = "not_converged"
                history.message = (
                    f"the step from t = {at.time:g} s to {at.time + self.h:g} s did not converge "
                    f"(residual {norm:.3g} after full Newton): try a smaller step"
                )
                return at
            at = self.advance(history, at, state, monitor, self.h, p=self.end_column(inputs[0], settled))
        return at

    def rescue(self, at: Resume, step_inputs, h: float):
        p1, pdot1, pddot1 = step_inputs
        state, monitor, norm = (
            np.asarray(q, dtype=float).ravel()
            for q in self.engine.rescue(at.state, h, p1, pdot1, pddot1, self.damping, self.mask, *self.data)
        )
        return state, monitor, float(norm[0])

    def accept(self, history, at: Resume, S, monitors, P, count: int, h: float, final: bool = False) -> Resume:
        """The window's first `count` steps (in steps h): works summed, every `every`-th kept."""
        if count == 0:
            return at
        previous = np.column_stack([at.monitor, monitors[:, : count - 1]])
        works = at.works[:, None] + np.cumsum(self.work_increments(previous, monitors[:, :count], h), axis=1)
        start = at
        for j in range(count):
            step, last = start.step + j + 1, j == count - 1
            now = self.time_of(step, start, h * (j + 1))
            kept = (step - start.inserted) % self.every == 0 or (last and final) or now >= self.until * (1 - 1e-12)
            if kept or last:
                at = Resume(
                    step,
                    S[:, j].copy(),
                    works[:, j],
                    monitors[:, j].copy(),
                    now,
                    start.h,
                    start.inserted,
                    start.onset_speeds,
                )
            if kept:
                self.keep(history, at, self.end_column(P, j))
        return at

    def advance(
        self,
        history,
        at: Resume,
        state,
        monitor,
        h: float,
        final: bool = False,
        p=None,
        time=None,
        kept: bool = False,
        speeds=None,
        inserted: int | None = None,
    ) -> Resume:
        """One step h on from `at`; `time`, `speeds` and `inserted` given for a step onto a
        contact's onset (service.dynamics.onsets), which is `kept`."""
        works = at.works + self.work_increments(np.asarray(at.monitor), np.asarray(monitor), h)
        step = at.step + 1
        now = Resume(
            step,
            np.array(state),
            works,
            np.array(monitor),
            self.time_of(step, at, h) if time is None else time,
            at.h,
            at.inserted if inserted is None else inserted,
            at.onset_speeds if speeds is None else speeds,
        )
        if kept or (now.step - now.inserted) % self.every == 0 or final or self.done(now):
            self.keep(history, now, p)
        return now

    def time_of(self, step: int, at: Resume, h: float) -> float:
        return (step - at.inserted) * self.h  # fixed steps: no sum of rounding errors


def _keep(history: History, t, state, n, p, monitor, works) -> None:
    history.times.append(t)
    history.x.append(state[:n].copy())
    history.v.append(state[n : 2 * n].copy())
    history.acceleration.append(state[3 * n : 4 * n].copy())
    history.lam.append(state[4 * n :].copy())
    history.p.append(np.array(p, dtype=float))
    history.motion_forces.append(np.array(monitor[6:]))
    history.kinetic.append(float(monitor[0]))
    history.potential.append(float(monitor[1]))
    history.input_work.append(float(works[0]))
    history.damping_work.append(float(works[1]))
    history.friction_work.append(float(works[2]))
    history.contact_damping_work.append(float(works[3]))
