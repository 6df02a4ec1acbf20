"""Where job tasks run: a process pool on this machine (default) or a Dask cluster.

Both are concurrent.futures executors, so the runner treats them alike. Worker processes
import flexmech once and keep their compiled mechanisms and CasADi Functions between tasks
(service.jobs.sweep caches them per document, models.assembly per structure). No CasADi
object ever crosses a process boundary: tasks carry JSON-able specs only.
"""

from __future__ import annotations

import logging
import multiprocessing
from abc import ABC, abstractmethod
from concurrent.futures import Executor, ProcessPoolExecutor

log = logging.getLogger("flexmech.executors")


class TaskExecutor(ABC):
    """Owns a concurrent.futures executor and knows how to make a new one if it breaks."""

    description: str
    capacity: int  # tasks worth keeping in flight

    @abstractmethod
    def executor(self) -> Executor: ...

    def renew(self) -> None:
        """Replace a broken executor (a process-pool worker died). A Dask cluster replaces
        lost workers itself, so by default there is nothing to do."""

    @abstractmethod
    def close(self) -> None: ...


class ProcessPool(TaskExecutor):
    def __init__(self, workers: int):
        self.workers = workers
        self.capacity = 2 * workers
        self.description = f"process pool ({workers} workers)"
        self._pool = self._new()

    def _new(self) -> ProcessPoolExecutor:
        # spawn: the server has threads (uvicorn, the solver thread); forking them is unsafe.
        return ProcessPoolExecutor(self.workers, mp_context=multiprocessing.get_context("spawn"))

    def executor(self) -> Executor:
        return self._pool

    def renew(self) -> None:
        log.warning("process pool broke; starting a new one")
        self._pool.shutdown(wait=False, cancel_futures=True)
        self._pool = self._new()

    def close(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)


class DaskCluster(TaskExecutor):
    def __init__(self, address: str, timeout: float = 30.0):
        from distributed import Client  # imported only when a cluster is configured

        self.address = address
        self._client = Client(address, timeout=timeout, set_as_default=False)
        workers = max(1, len(self._client.scheduler_info(n_workers=-1).get("workers", {})))
        self.capacity = 2 * workers
        self.description = f"Dask cluster at {address} ({workers} workers)"
        self._executor = self._client.get_executor(pure=False)

    def executor(self) -> Executor:
        return self._executor

    def close(self) -> None:
        self._client.close()


def make_executor(dask_address: str | None, workers: int) -> TaskExecutor:
    if dask_address:
        return DaskCluster(dask_address)
    return ProcessPool(workers)
