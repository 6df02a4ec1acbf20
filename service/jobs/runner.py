"""The job runner: one thread that feeds tasks of active jobs to an executor and stores the
points each task returns, as it returns them.

On start it takes up every job the store lists as queued or running, including jobs a
previous server process left running: their stored points are kept and only the missing ones
are computed (the kind decides the tasks from the stored points). A cancelled job, or one
over its time limit, stops getting tasks, and the points of its tasks still running are
dropped: after the cancel is seen, its stored points do not change.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from concurrent.futures import FIRST_COMPLETED, Future, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field

from service.jobs.executors import TaskExecutor
from service.jobs.kinds import JobKind, kind_named, run_task
from service.jobs.store import Job, JobStore

log = logging.getLogger("flexmech.runner")

MAX_TASK_ATTEMPTS = 2  # a task whose worker died is tried once more before its job fails


@dataclass
class _ActiveJob:
    job: Job
    kind: JobKind
    finished: dict[int, dict]
    pending: deque
    activated: float  # time.monotonic() when this process took the job up
    in_flight: dict[Future, dict] = field(default_factory=dict)
    attempts: dict[int, int] = field(default_factory=dict)  # id(task) -> attempts


class JobRunner:
    def __init__(self, store: JobStore, executor: TaskExecutor, chunk_size: int = 8,
                 job_time_limit: float = 3600.0, poll_seconds: float = 0.2):
        self.store = store
        self.executor = executor
        self.chunk_size = chunk_size
        self.job_time_limit = job_time_limit
        self.poll_seconds = poll_seconds
        self._active: dict[str, _ActiveJob] = {}
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._generation = 0  # bumped when the executor is renewed
        self._born: dict[Future, int] = {}  # executor generation each future was submitted to
        self._last_look = -float("inf")  # when the store was last asked for new and cancelled jobs

    # --- control ---------------------------------------------------------------------------
    def start(self) -> None:
        self._thread = threading.Thread(target=self._loop, name="flexmech-job-runner", daemon=True)
        self._thread.start()

    def wake(self) -> None:
        """A job was created or cancelled: look at the store now rather than at the next poll."""
        self._wake.set()

    def stop(self, timeout: float = 10.0) -> None:
        """Stop taking tasks; running jobs stay 'running' in the store and resume next start."""
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout)

    @property
    def alive(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    # --- the loop --------------------------------------------------------------------------
    def _loop(self) -> None:
        while not self._stop.is_set():
            try:
                self._step()
            except Exception:  # the loop must survive a bad job or a store hiccup; it logs and goes on
                log.exception("job runner step failed")
                time.sleep(self.poll_seconds)

    def _step(self) -> None:
        now = time.monotonic()
        if self._wake.is_set() or now - self._last_look >= self.poll_seconds:
            self._wake.clear()
            self._last_look = now
            self._take_up_new_jobs()
            self._drop_finished_jobs()
        self._submit()
        futures = [f for a in self._active.values() for f in a.in_flight]
        if futures:
            done, _ = wait(futures, timeout=self.poll_seconds, return_when=FIRST_COMPLETED)
            for future in done:
                self._collect(future)
        else:
            self._wake.wait(self.poll_seconds)
        for job_id in list(self._active):
            self._maybe_complete(self._active[job_id])

    def _take_up_new_jobs(self) -> None:
        for job in self.store.active():
            if job.id in self._active:
                continue
            resumed = job.status == "running"
            try:
                kind = kind_named(job.kind)
                finished = self.store.points(job.id)
                tasks = kind.tasks(job.spec, job.plan, finished, self.chunk_size)
            except Exception as exc:  # a job this server cannot run is failed, not retried forever
                self.store.finish(job.id, "failed", f"cannot start: {exc}")
                continue
            self.store.mark_started(job.id, resumed)
            if resumed:
                log.info("resuming job %s: %d of %d points already stored", job.id, len(finished), job.total)
            self._active[job.id] = _ActiveJob(job, kind, finished, deque(tasks), time.monotonic())

    def _drop_finished_jobs(self) -> None:
        """Jobs cancelled through the API (their status is final in the store), and jobs over
        their time limit."""
        for job_id, active in list(self._active.items()):
            current = self.store.get(job_id)
            if current is None or current.status not in ("queued", "running"):
                self._abandon(active)
            elif time.monotonic() - active.activated > self.job_time_limit:
                self.store.finish(job_id, "failed", f"stopped by the job time limit of {self.job_time_limit:g} s; "
                                                    f"{len(active.finished)} of {active.job.total} points are stored")
                self._abandon(active)

    def _abandon(self, active: _ActiveJob) -> None:
        for future in active.in_flight:
            future.cancel()
            self._born.pop(future, None)
        del self._active[active.job.id]

    def _submit(self) -> None:
        in_flight = sum(len(a.in_flight) for a in self._active.values())
        progressed = True
        while in_flight < self.executor.capacity and progressed:
            progressed = False
            for active in list(self._active.values()):  # one task per job per round: fair sharing
                if active.pending and in_flight < self.executor.capacity:
                    task = active.pending[0]
                    try:
                        future = self.executor.executor().submit(run_task, active.job.kind, active.job.spec, task)
                    except BrokenProcessPool:  # a worker died since the last look: new pool, same task
                        self._renew_executor()
                        return
                    active.pending.popleft()
                    active.in_flight[future] = task
                    self._born[future] = self._generation
                    in_flight += 1
                    progressed = True

    def _collect(self, future: Future) -> None:
        owner = next((a for a in self._active.values() if future in a.in_flight), None)
        if owner is None:
            return
        task = owner.in_flight.pop(future)
        born = self._born.pop(future, self._generation)
        if future.cancelled():
            return
        error = future.exception()
        if error is not None:
            self._task_failed(owner, task, error, born)
            return
        points = future.result()
        self.store.add_points(owner.job.id, points, owner.kind.failed)
        owner.finished.update(points)
        owner.pending.extend(owner.kind.follow_up(owner.job.spec, owner.job.plan, task, owner.finished,
                                                  self.chunk_size))

    def _task_failed(self, active: _ActiveJob, task: dict, error: BaseException, born: int) -> None:
        key = id(task)
        active.attempts[key] = active.attempts.get(key, 0) + 1
        if isinstance(error, BrokenProcessPool):
            if born == self._generation:  # the first to notice renews the pool, for every job
                self._renew_executor()
            if active.attempts[key] < MAX_TASK_ATTEMPTS:
                active.pending.appendleft(task)
                return
        log.error("job %s: task failed: %r", active.job.id, error)
        self.store.finish(active.job.id, "failed", f"a task failed: {type(error).__name__}: {error}")
        self._abandon(active)

    def _renew_executor(self) -> None:
        self.executor.renew()
        self._generation += 1

    def _maybe_complete(self, active: _ActiveJob) -> None:
        if active.pending or active.in_flight:
            return
        stored = len(active.finished)
        if stored < active.job.total:
            self.store.finish(active.job.id, "failed", f"only {stored} of {active.job.total} points could be computed")
        else:
            self.store.finish(active.job.id, "succeeded")
        del self._active[active.job.id]
