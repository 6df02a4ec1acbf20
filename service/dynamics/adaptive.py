"""Adaptive steps: the step follows an estimate of each step's local error, the Newmark
family's (Zienkiewicz and Xie 1991)

    e = |beta - 1/6| h^2 |qdd_{n+1} - qdd_n|_inf,

the difference between the scheme's displacement and a third-order one (nondimensional:
lengths per the mechanism's length scale, angles in rad), or a stage scheme's embedded
estimate (service.dynamics.stage_window). A window of up to ADAPTIVE_WINDOW steps (a stage
scheme's: fewer, service.dynamics.stepping.window_length) is run in one step size; its steps
are accepted up to the first whose error exceeds the tolerance, and the next step is
h (tol / e)^(1/3) (a stage scheme's: ^(1/order)) with a safety factor, at most twice the last
and at most max_step. A step that the window's factors did not settle (they were made at the
window's first step) is no error: the next window starts there with the same step and new
factors. The last window ends on `until` exactly. A step that enters a damped contact is
replaced by steps onto its onset (service.dynamics.onsets). A run stops with status step_limit after
max_steps accepted steps, min_step when the step would fall below min_step."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexmech.service.dynamics.onsets import crossing, step_onto_onset
from flexmech.service.dynamics.stepping import History, Resume, StepRunner

SAFETY = 0.9
ADAPTIVE_WINDOW = 50  # steps per window of one step size: the step controller adapts once per window
MAX_REJECTIONS = 12  # in a row: then the run ends, not_converged
SHRINK_AT_MOST, GROW_AT_MOST = 0.2, 2.0
# A stage scheme's second rejection in a row at least halves its step: where its error falls
# slower than its order says (sdirk4's h^4 is h^1.5 while the four-bar's coupler buckles), the
# order's shrink, 3 % a try there, would spend every try.
REJECTED_AGAIN = 0.5


@dataclass(frozen=True)
class Tolerance:
    local: float = 1e-6  # a step's local error (nondimensional)
    max_step: float = math.inf  # seconds
    min_step: float = 1e-9  # seconds: a step that must be shorter ends the run (status min_step)
    max_steps: int = 1_000_000  # accepted steps: more ends the run (status step_limit)


class AdaptiveRunner(StepRunner):
    window_steps = ADAPTIVE_WINDOW

    def __init__(self, *args, tolerance: Tolerance):
        super().__init__(*args)
        self.tolerance = tolerance
        # the local error grows as h^(order + 1) of the estimate's lower-order solution
        self.exponent = 1 / 3 if self.stages == 1 else 1 / self.scheme.order

    def local_errors(self, at: Resume, S: np.ndarray, count: int, h: float) -> np.ndarray:
        """Each of the window's first `count` steps' local error estimate (nondimensional)."""
        n = self.n
        if self.stages > 1:  # a stage scheme's embedded estimate, in the state (service.dynamics.stage_window)
            return np.abs(S[2 * n : 3 * n, :count]).max(axis=0, initial=0.0)
        accelerations = np.column_stack([at.state[3 * n : 4 * n], S[3 * n : 4 * n, :count]])
        return abs(self.scheme.beta - 1 / 6) * h**2 * np.abs(np.diff(accelerations, axis=1)).max(axis=0, initial=0.0)

    def _retry(self, h: float, error: float | None, again: bool) -> float:
        """The step after a rejected first step h: halved where it did not settle (error None)
        or its error is not finite, else shrunk by the error; a stage scheme's rejected again at
        least halved (REJECTED_AGAIN)."""
        shrink = 0.5 if error is None or not np.isfinite(error) else self._shrink(error)
        return h * (min(shrink, REJECTED_AGAIN) if again and self.stages > 1 else shrink)

    def _shrink(self, error: float) -> float:
        return _shrink(self.tolerance.local, error, self.exponent)

    def done(self, at: Resume) -> bool:
        return at.time >= self.until * (1 - 1e-12)

    def time_of(self, step: int, at: Resume, h: float) -> float:
        t = at.time + h
        return self.until if abs(t - self.until) <= 1e-9 * self.until else t  # the last step ends on until

    def window(self, history: History, at: Resume) -> Resume:
        h, tol = min(at.h or self.h, self.tolerance.max_step), self.tolerance.local
        left = self.tolerance.max_steps - at.step
        if left <= 0:
            history.status = "step_limit"
            history.message = (
                f"stopped at t = {at.time:g} s of {self.until:g} s: the run took its limit of "
                f"{self.tolerance.max_steps} adaptive steps (last step {h:.3g} s); loosen the "
                "tolerance or shorten the run"
            )
            return at
        for rejected in range(MAX_REJECTIONS):
            remaining = self.until - at.time
            needed = math.ceil(min(remaining / h, 1e15) - 1e-9)  # never an infinite count
            size = self.window_steps
            count, h_use = (needed, remaining / needed) if needed <= size else (size, h)
            count = min(count, left)
            if h_use < self.tolerance.min_step:
                history.status = "min_step"
                history.message = (
                    f"stopped at t = {at.time:g} s of {self.until:g} s: the step fell below "
                    f"min_step = {self.tolerance.min_step:g} s (a loss of convergence or an "
                    "impact-like event); loosen the tolerance"
                )
                return at
            inputs, S, monitors, iterations, settled = self.run_window(at, h_use, count)
            if S is None:
                h = 0.5 * h_use
                continue
            errors = self.local_errors(at, S, count, h_use)
            too_large = [j for j in range(settled) if not errors[j] <= tol]
            first_bad = too_large[0] if too_large else settled
            if first_bad == 0:
                # not settled on the window's first factors (made at this very step), or too large
                h = self._retry(h_use, errors[0] if too_large else None, rejected > 0)
                continue
            entering = crossing(self, at, inputs, S, first_bad)
            if entering is not None:  # a damped contact begins within a step: step onto its onset
                history.iterations += int(iterations[: entering[0]].sum())
                at = self.accept(history, at, S, monitors, inputs[0], entering[0], h_use)
                at = step_onto_onset(self, history, at, entering[1], entering[2], h_use)
                at.h = h_use
                return at
            history.iterations += int(iterations[:first_bad].sum())
            at = self.accept(history, at, S, monitors, inputs[0], first_bad, h_use, first_bad == count == needed)
            if too_large:
                grow = self._shrink(errors[first_bad])
            elif settled < count:  # the window's factors aged: the next window makes new ones, same step
                grow = 1.0
            else:
                grow = min(GROW_AT_MOST, _ratio(tol, errors[:count].max(), self.exponent))
            at.h = min(h_use * grow, self.tolerance.max_step)
            return at
        history.status = "not_converged"
        history.message = (
            f"at t = {at.time:g} s the first step was rejected {MAX_REJECTIONS} times in a row, down to "
            f"{h:.3g} s: the motion cannot be followed from here (a loss of convergence)"
        )
        return at


def _ratio(tol: float, error: float, exponent: float) -> float:
    return SAFETY * (tol / max(error, 1e-300)) ** exponent


def _shrink(tol: float, error: float, exponent: float) -> float:
    return max(SHRINK_AT_MOST, min(SAFETY, _ratio(tol, error, exponent)))
