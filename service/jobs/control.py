"""In a worker: whether the running task should stop, because its job was cancelled or is out
of time, or because the runner asked it to give its worker to another key's job (it then
returns the points it has; the runner keeps them and queues the rest: service.jobs.fair_share). A task carries its job's deadline (time.time() seconds) and a stop signal (a flag
file for the process pool, a Dask Event on a cluster: service.jobs.executors). Kinds check
between points, give Newton the time left, and hand should_stop to IPOPT's iteration hook.
"""

from __future__ import annotations

import os
import threading
import time

from flexmech.service.threads import single_threaded_blas

CHECK_EVERY = 0.2  # seconds between looks at the stop signal (a Dask Event is a round trip)


class TaskControl:
    def __init__(self, task: dict):
        self.deadline: float | None = task.get("deadline")
        signal = task.get("control") or {}
        self._file = signal.get("file")
        self._event = signal.get("dask_event")
        self._yield_file = signal.get("yield_file")
        self._yield_event = signal.get("yield_event")
        self._checked, self._cancelled, self._yield = 0.0, False, False
        self.interrupted = False  # stop_or_yield() said True to a loop

    def remaining(self) -> float | None:
        """Seconds until the job's deadline (None: no deadline)."""
        return None if self.deadline is None else self.deadline - time.time()

    def cancelled(self) -> bool:
        self._look()
        return self._cancelled

    def should_yield(self) -> bool:
        """Whether the runner asked this task to give its worker to another key's job: checked
        between points (a point in progress is finished, so its result is whole)."""
        self._look()
        return self._yield

    def _look(self) -> None:
        if self._cancelled or time.monotonic() - self._checked < CHECK_EVERY:
            return
        self._checked = time.monotonic()
        if self._file is not None:
            self._cancelled = os.path.exists(self._file)
            self._yield = self._yield or bool(self._yield_file and os.path.exists(self._yield_file))
        elif self._event is not None:
            from distributed import Event, get_client

            client = get_client()
            self._cancelled = Event(self._event, client=client).is_set()
            self._yield = self._yield or bool(self._yield_event and Event(self._yield_event, client=client).is_set())

    def stop_reason(self) -> str | None:
        """'cancelled', 'time_limit' or None."""
        if self.cancelled():
            return "cancelled"
        remaining = self.remaining()
        return "time_limit" if remaining is not None and remaining <= 0 else None

    def should_stop(self) -> bool:
        return self.stop_reason() is not None

    def between_points(self) -> bool:
        """Whether to end the task before its next point: stopped, or asked to yield."""
        return self.should_stop() or self.should_yield()

    def stop_or_yield(self) -> bool:
        """The stop of work that cannot be kept in part (an export, an analysis job, an
        optimization's start, an impact run): it ends when stopped or asked to yield, and runs
        again from its start later. `interrupted` remembers that a loop was told so."""
        if self.between_points():
            self.interrupted = True
        return self.interrupted

    def yielded_midway(self) -> bool:
        """Whether stop_or_yield() ended a loop for a yield (not a cancel or the time limit)."""
        return self.interrupted and not self.should_stop()

    def time_limit(self, per_solve: float | None) -> float | None:
        """The time a solve may take: its own limit, within what is left of the job's."""
        remaining = self.remaining()
        if remaining is None:
            return per_solve
        remaining = max(remaining, 1e-3)
        return remaining if per_solve is None else min(per_solve, remaining)


def worker_started() -> None:
    """A process-pool worker's first act: one BLAS thread, and an end when the server ends."""
    single_threaded_blas()
    parent = os.getppid()

    def watch() -> None:  # orphaned (the server was killed): stop computing what nobody waits for
        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(0)

    threading.Thread(target=watch, name="flexmech-parent-watch", daemon=True).start()
