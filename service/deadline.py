"""When a solving loop must stop: one clock per solver-worker call.

Every loop that a time limit bounds (Newton, IPOPT, a trace, a simulation's windows, a
drawing's frames) asks ends_after(limit) when it starts. Outside a call scope that is now +
limit, per loop. Inside one (a solver worker's call, api.solver_pool) the call has one
deadline, set by its first loop and never moved later: a target solve's Newton runs, a trace's
points and the drawing after them share the limit. The deadline is published to a shared value
that the server reads, so it can replace a worker that is still busy 1 s past it: before the
first loop starts (building a new structure's graphs, bounded by the document's costing), the
server allows its build allowance instead.

The clock is time.monotonic(): Linux's CLOCK_MONOTONIC, the same in the server and its workers.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from contextlib import contextmanager


class _Scope:
    def __init__(self, shared):
        self.deadline: float | None = None
        self.shared = shared  # a multiprocessing Value('d') the server reads (0: no loop yet), or None


_scope: _Scope | None = None


@contextmanager
def call_scope(shared=None):
    """One call's clock: loops within share the deadline of the first; `shared` publishes it."""
    global _scope
    _scope = _Scope(shared)
    if shared is not None:
        shared.value = 0.0
    try:
        yield
    finally:
        _scope = None
        if shared is not None:
            shared.value = 0.0


def ends_after(seconds: float | None) -> float:
    """The time.monotonic() at which a loop given `seconds` stops (inf: never)."""
    if seconds is None:
        return math.inf
    end = time.monotonic() + seconds
    if _scope is None:
        return end
    if _scope.deadline is None or end < _scope.deadline:
        _scope.deadline = end
        if _scope.shared is not None:
            _scope.shared.value = end
    return _scope.deadline


_stopped: Callable[[], bool] | None = None  # inside a job task: whether its job was cancelled


@contextmanager
def stop_scope(stopped: Callable[[], bool]):
    """Inside a job task (service.jobs.kinds.run_task): every loop that asks passed() (or
    stop_requested()) also ends when `stopped()` says the job was cancelled or is out of time (a cheap look: service.jobs.control reads its
    signal at most every 0.2 s), so a cancel ends a Newton run, a trace or a simulation window
    within a moment, not at its own time limit."""
    global _stopped
    outer, _stopped = _stopped, stopped
    try:
        yield
    finally:
        _stopped = outer  # a scope within a task's (an export's, asked to yield too) gives it back


def stop_requested() -> bool:
    """Inside a job task: whether its job was cancelled or is out of time (else False)."""
    return _stopped is not None and _stopped()


def passed(end: float) -> bool:
    return time.monotonic() > end or stop_requested()
