"""In a worker: whether the running task should stop, because its job was cancelled or is out
of time. A task carries its job's deadline (time.time() seconds) and a stop signal (a flag
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
        self._checked, self._cancelled = 0.0, False

    def remaining(self) -> float | None:
        """Seconds until the job's deadline (None: no deadline)."""
        return None if self.deadline is None else self.deadline - time.time()

    def cancelled(self) -> bool:
        if self._cancelled or time.monotonic() - self._checked < CHECK_EVERY:
            return self._cancelled
        self._checked = time.monotonic()
        if self._file is not None:
            self._cancelled = os.path.exists(self._file)
        elif self._event is not None:
            from distributed import Event, get_client

            self._cancelled = Event(self._event, client=get_client()).is_set()
        return self._cancelled

    def stop_reason(self) -> str | None:
        """'cancelled', 'time_limit' or None."""
        if self.cancelled():
            return "cancelled"
        remaining = self.remaining()
        return "time_limit" if remaining is not None and remaining <= 0 else None

    def should_stop(self) -> bool:
        return self.stop_reason() is not None

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
