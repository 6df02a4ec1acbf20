"""Time integration of the dynamics form from a start (or a stored Resume) to an end time,
in fixed steps (service.dynamics.stepping) or adaptive ones (service.dynamics.adaptive)."""

from __future__ import annotations

import time

import numpy as np

from flexmech.models.graph.structure import Structure
from flexmech.service.dynamics.adaptive import AdaptiveRunner, Tolerance
from flexmech.service.dynamics.histories import Histories, no_histories
from flexmech.service.dynamics.schemes import Scheme
from flexmech.service.dynamics.stepping import History, Resume, StepRunner, start_of

__all__ = ["History", "Resume", "Tolerance", "integrate", "start_of"]


def integrate(
    structure: Structure,
    p: np.ndarray,
    x0: np.ndarray,
    v0: np.ndarray,
    until: float,
    h: float,
    scheme: Scheme,
    damping: float = 0.0,
    every: int = 1,
    stop=None,
    histories: Histories | None = None,
    progress=None,
    resume: Resume | None = None,
    adaptive=None,
) -> History:
    """States from t = 0 (or from `resume`) to `until` in steps h (seconds), keeping every
    `every`-th step (and the start, when not resumed). Steps run in windows of one Function
    call each (service.dynamics.engine, on the element kernels the cache has compiled); a step
    the window's modified Newton does not settle is retried by full Newton before the run stops. With `adaptive` (an
    service.dynamics.adaptive.Tolerance), h is the first step and the step follows the local
    error. `stop()` true ends the run early; `progress(t, steps)` hears after every window.
    history.resume goes on from the end."""
    started = time.perf_counter()
    histories = histories or no_histories()
    if adaptive is None:
        runner = StepRunner(structure, p, h, scheme, damping, histories, until, every)
    else:
        runner = AdaptiveRunner(structure, p, h, scheme, damping, histories, until, every, tolerance=adaptive)
    history = History("finished", "")
    if resume is None:
        resume = start_of(structure, p, x0, v0, histories, damping, scheme)
        resume.h = h
        runner.keep(history, resume)
    while not runner.done(resume):
        if stop is not None and stop():
            history.status, history.message = "stopped", f"stopped at t = {resume.time:g} s"
            break
        resume = runner.window(history, resume)
        if history.status != "finished":
            break
        if progress is not None:
            progress(resume.time, resume.step)
    history.steps, history.resume = resume.step, resume
    history.kernels = runner.engine.kernels()
    history.seconds = time.perf_counter() - started
    return history
