"""Adaptive steps: the step follows an estimate of each step's local error, the Newmark
family's (Zienkiewicz and Xie 1991)

    e = |beta - 1/6| h^2 |qdd_{n+1} - qdd_n|_inf,

the difference between the scheme's displacement and a third-order one (nondimensional:
lengths per the mechanism's length scale, angles in rad). A window is run in one step size;
its steps are accepted up to the first whose error exceeds the tolerance or whose Newton did
not settle, and the next step is h (tol / e)^(1/3) with a safety factor, at most twice the
last and at most max_step. The last window ends on `until` exactly."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from service.dynamics.stepping import History, Resume, StepRunner
from service.dynamics.window import WINDOW

SAFETY = 0.9
MAX_REJECTIONS = 12  # in a row: then the run ends, not_converged
SHRINK_AT_MOST, GROW_AT_MOST = 0.2, 2.0


@dataclass(frozen=True)
class Tolerance:
    local: float = 1e-6  # a step's local error (nondimensional)
    max_step: float = math.inf  # seconds
    min_step: float = 1e-9


class AdaptiveRunner(StepRunner):
    def __init__(self, *args, tolerance: Tolerance):
        super().__init__(*args)
        self.tolerance = tolerance
        self.factor = abs(self.scheme.beta - 1 / 6)

    def done(self, at: Resume) -> bool:
        return at.time >= self.until * (1 - 1e-12)

    def time_of(self, step: int, at: Resume, h: float) -> float:
        t = at.time + h
        return self.until if abs(t - self.until) <= 1e-9 * self.until else t  # the last step ends on until

    def window(self, history: History, at: Resume) -> Resume:
        h, tol, n = min(at.h or self.h, self.tolerance.max_step), self.tolerance.local, self.n
        for _ in range(MAX_REJECTIONS):
            remaining = self.until - at.time
            needed = math.ceil(remaining / h - 1e-9)
            count, h_use = (needed, remaining / needed) if needed <= WINDOW else (WINDOW, h)
            if h_use < self.tolerance.min_step:
                history.status = "not_converged"
                history.message = (f"at t = {at.time:g} s the step fell below min_step = {self.tolerance.min_step:g} s "
                                   "(a loss of convergence or an impact-like event): loosen the tolerance")
                return at
            inputs, S, monitors, settled = self.run_window(at, h_use)
            if S is None:
                h = 0.5 * h_use
                continue
            accelerations = np.column_stack([at.state[3 * n:4 * n], S[3 * n:4 * n, :count]])
            errors = self.factor * h_use**2 * np.abs(np.diff(accelerations, axis=1)).max(axis=0, initial=0.0)
            bad = [j for j in range(count) if j >= settled or not errors[j] <= tol]
            first_bad = bad[0] if bad else count
            if first_bad == 0:
                h = h_use * (0.5 if settled == 0 or not np.isfinite(errors[0]) else _shrink(tol, errors[0]))
                continue
            at = self.accept(history, at, S, monitors, inputs[0], first_bad, h_use, first_bad == count == needed)
            worst = errors[first_bad] if first_bad < count else errors[:first_bad].max()
            grow = _shrink(tol, worst) if first_bad < count else min(GROW_AT_MOST, _ratio(tol, worst))
            at.h = min(h_use * grow, self.tolerance.max_step)
            return at
        history.status = "not_converged"
        history.message = (f"at t = {at.time:g} s the first step was rejected {MAX_REJECTIONS} times in a row, down to "
                           f"{h:.3g} s: the motion cannot be followed from here (a loss of convergence)")
        return at


def _ratio(tol: float, error: float) -> float:
    return SAFETY * (tol / max(error, 1e-300)) ** (1 / 3)


def _shrink(tol: float, error: float) -> float:
    return max(SHRINK_AT_MOST, min(SAFETY, _ratio(tol, error)))
