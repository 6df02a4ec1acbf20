"""Where job tasks run: a process pool on this machine (default) or a Dask cluster.

Both are concurrent.futures executors, so the runner treats them alike. Worker processes
import flexmech once and keep their compiled mechanisms and CasADi Functions between tasks
(service.jobs.sweep caches them per document, models.graph.assembly per structure, and built
graphs are on disk for every new worker). No CasADi object ever crosses a process boundary:
tasks carry JSON-able specs only.

Each executor also carries stop signals to running tasks (service.jobs.control reads them):
a flag file per job for the process pool, a Dask Event per job on a cluster. A process pool
can kill its workers (a task that will not stop, or the server shutting down); a Dask
cluster's workers are the cluster's to manage.
"""

from __future__ import annotations

import logging
import multiprocessing
import shutil
import signal
import tempfile
import time
from abc import ABC, abstractmethod
from concurrent.futures import Executor, ProcessPoolExecutor
from pathlib import Path

from flexmech.service.jobs.control import worker_started

log = logging.getLogger("flexmech.executors")


class TaskExecutor(ABC):
    """Owns a concurrent.futures executor and knows how to make a new one if it breaks."""

    description: str
    workers: int  # tasks that run at once
    capacity: int  # tasks worth keeping in flight (some wait in the executor's queue)

    def __init__(self):
        self._signalled: dict[str, float] = {}  # job id -> time.monotonic() of its stop signal

    @abstractmethod
    def executor(self) -> Executor: ...

    def renew(self) -> None:  # noqa: B027 (an optional hook: nothing to do by default)
        """Replace a broken executor (a process-pool worker died). A Dask cluster replaces
        lost workers itself, so by default there is nothing to do."""

    def kill(self) -> bool:
        """Stop every worker now, whatever it runs; False where this executor cannot."""
        return False

    @abstractmethod
    def control_for(self, job_id: str) -> dict:
        """What a task of the job carries to learn that it should stop (JSON)."""

    def stop(self, job_id: str) -> None:
        """Tell the job's running tasks to stop."""
        self._signalled[job_id] = time.monotonic()

    @abstractmethod
    def yield_signal_for(self, task_id: str) -> dict:
        """What one task carries to learn that it should give its worker up (JSON)."""

    @abstractmethod
    def ask_to_yield(self, task_id: str) -> None:
        """Tell one task to end after the point in progress (its points so far are kept)."""

    @abstractmethod
    def forget_task(self, task_id: str) -> None:
        """The task has ended: drop its yield signal."""

    def died_running(self, task_id: str) -> bool:
        """Whether the task's own worker died under it (not one stopped because another worker
        died). By default every task lost with a broken executor is taken as its cause."""
        return True

    def task_ended(self, task_id: str) -> None:  # noqa: B027 (an optional hook)
        """The task has ended, however: drop what the executor kept of it."""

    def signalled_before(self, moment: float) -> list[str]:
        """Jobs whose stop signal was given before `moment` (time.monotonic())."""
        return sorted(job_id for job_id, when in self._signalled.items() if when < moment)

    def forget(self, job_id: str) -> None:
        """The job's tasks have all ended: drop its stop signal."""
        self._signalled.pop(job_id, None)

    @abstractmethod
    def close(self) -> None: ...


class ProcessPool(TaskExecutor):
    def __init__(self, workers: int, flags: Path | None = None):
        """flags: where the stop signals go (default: a new folder in the system's temp)."""
        super().__init__()
        self.workers = workers
        self.capacity = 2 * workers
        self.description = f"process pool ({workers} workers)"
        if flags is not None:
            flags.mkdir(parents=True, exist_ok=True)
        self._flags = Path(tempfile.mkdtemp(prefix="stop-", dir=flags))
        self._known: dict[int, multiprocessing.process.BaseProcess] = {}  # every worker, by pid (exit codes)
        self._pool = self._new()

    def _new(self) -> ProcessPoolExecutor:
        # spawn: the server has threads (uvicorn, the body parser, the solver pool's readers); forking them is unsafe.
        return ProcessPoolExecutor(
            self.workers, mp_context=multiprocessing.get_context("spawn"), initializer=worker_started
        )

    def executor(self) -> Executor:
        self._known.update(self._pool._processes or {})  # workers started since the last look
        return self._pool

    def renew(self) -> None:
        log.warning("process pool broke; starting a new one")
        self._end_pool()
        self._pool = self._new()

    def kill(self) -> bool:
        self._end_pool()
        self._pool = self._new()
        return True

    def _end_pool(self) -> None:
        """Shut the pool down and end its workers now (a running task included)."""
        # the pool's own workers, taken before shutdown drops them: not every child of this process
        # (the server's solver workers are children too, and must not die with a job's pool)
        workers = list((self._pool._processes or {}).values())
        self._pool.shutdown(wait=False, cancel_futures=True)
        for process in workers:
            process.terminate()
        for process in workers:
            process.join(5)
            if process.is_alive():
                process.kill()
                process.join(5)

    def control_for(self, job_id: str) -> dict:
        return {"file": str(self._flags / f"{job_id}.stop")}

    def yield_signal_for(self, task_id: str) -> dict:
        # the task writes its worker's pid beside: when the pool breaks, the dead worker's task is known
        return {"yield_file": str(self._flags / f"{task_id}.yield"), "pid_file": str(self._flags / f"{task_id}.pid")}

    def died_running(self, task_id: str) -> bool:
        """The task's worker (its pid file) ended other than by the pool's own terminate: it died
        under that task (killed, crashed, out of memory). A task not yet started, or whose
        worker the broken pool terminated, is not the cause."""
        try:
            pid = int((self._flags / f"{task_id}.pid").read_text())
        except (OSError, ValueError):
            return False
        self._known.update(self._pool._processes or {})
        process = self._known.get(pid)
        code = process.exitcode if process is not None else None
        return code is not None and code != -signal.SIGTERM

    def ask_to_yield(self, task_id: str) -> None:
        try:
            (self._flags / f"{task_id}.yield").touch()
        except OSError as exc:  # a full disk: the task runs on, and the waiting key waits for it
            log.warning("cannot ask a task to yield: %s", exc)

    def forget_task(self, task_id: str) -> None:
        (self._flags / f"{task_id}.yield").unlink(missing_ok=True)

    def task_ended(self, task_id: str) -> None:
        (self._flags / f"{task_id}.pid").unlink(missing_ok=True)

    def stop(self, job_id: str) -> None:
        super().stop(job_id)
        (self._flags / f"{job_id}.stop").touch()

    def forget(self, job_id: str) -> None:
        super().forget(job_id)
        (self._flags / f"{job_id}.stop").unlink(missing_ok=True)

    def close(self) -> None:
        self._end_pool()
        self._pool.shutdown(wait=True)  # joins the pool's own threads: nothing is left behind
        shutil.rmtree(self._flags, ignore_errors=True)


class DaskCluster(TaskExecutor):
    def __init__(self, address: str, timeout: float = 30.0):
        from distributed import Client  # imported only when a cluster is configured

        super().__init__()
        self.address = address
        self._client = Client(address, timeout=timeout, set_as_default=False)
        workers = max(1, len(self._client.scheduler_info(n_workers=-1).get("workers", {})))
        self.workers = workers
        self.capacity = 2 * workers
        # /v1/health shows this to anyone: the cluster's address stays in the server's log
        self.description = f"Dask cluster ({workers} workers)"
        log.info("Dask cluster at %s (%d workers)", address, workers)
        self._executor = self._client.get_executor(pure=False)

    def executor(self) -> Executor:
        return self._executor

    def control_for(self, job_id: str) -> dict:
        return {"dask_event": f"flexmech-stop-{job_id}"}

    def yield_signal_for(self, task_id: str) -> dict:
        return {"yield_event": f"flexmech-yield-{task_id}"}

    def ask_to_yield(self, task_id: str) -> None:
        from distributed import Event

        Event(f"flexmech-yield-{task_id}", client=self._client).set()

    def forget_task(self, task_id: str) -> None:
        from distributed import Event

        Event(f"flexmech-yield-{task_id}", client=self._client).clear()

    def stop(self, job_id: str) -> None:
        from distributed import Event

        super().stop(job_id)
        Event(f"flexmech-stop-{job_id}", client=self._client).set()

    def forget(self, job_id: str) -> None:
        from distributed import Event

        super().forget(job_id)
        Event(f"flexmech-stop-{job_id}", client=self._client).clear()

    def close(self) -> None:
        self._client.close()


def make_executor(dask_address: str | None, workers: int, data_dir: Path | None = None) -> TaskExecutor:
    if dask_address:
        return DaskCluster(dask_address)
    return ProcessPool(workers, None if data_dir is None else data_dir / "signals")
