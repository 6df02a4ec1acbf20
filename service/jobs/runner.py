"""The job runner: one thread that feeds tasks of active jobs to an executor and stores the
points each task returns, as it returns them.

On start it takes up every job the store lists as queued or running, including jobs a
previous server process left running: their stored points are kept and only the missing ones
are computed (the kind decides the tasks from the stored points).

Stopping: every task carries its job's deadline and a stop signal (service.jobs.control). A
cancelled job, or one over its time limit, stops getting tasks; its running tasks are told to
stop (they check between points; Newton and the other timed loops see the stop as their time
limit, IPOPT every iteration), and a task
that has not stopped after STOP_GRACE seconds has its workers killed (a process pool is
renewed; tasks of other jobs lost that way are run again, not counted as failures). After the
cancel is seen, the job's stored points do not change.

The store may fail (a locked SQLite file, a full disk): points that could not be written are
kept and written again with backoff (service.jobs.store_guard), so none is lost, and a job
is finished only once all its points are stored.

Tasks are sent fairly between keys, and taken back without loss (service.jobs.runner_tasks,
service.jobs.fair_share); a job whose points take its key past the byte quota stops there
(service.jobs.quotas).
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from concurrent.futures import FIRST_COMPLETED, Future, wait

from flexmech.service.jobs.base import task_remainder
from flexmech.service.jobs.executors import TaskExecutor
from flexmech.service.jobs.kinds import kind_named
from flexmech.service.jobs.runner_tasks import ActiveJob, TaskFeeding
from flexmech.service.jobs.store import JobStore
from flexmech.service.jobs.store_guard import StoreGuard

log = logging.getLogger("flexmech.runner")

STOP_GRACE = 1.5  # seconds a told-to-stop task may run on before its workers are killed (theirs run again)


class JobRunner(TaskFeeding):
    def __init__(
        self,
        store: JobStore,
        executor: TaskExecutor,
        chunk_size: int = 8,
        job_time_limit: float = 3600.0,
        poll_seconds: float = 0.2,
    ):
        self.store = store
        self.guard = StoreGuard(on_recovery=store.compact)
        self.executor = executor
        self.chunk_size = chunk_size
        self.job_time_limit = job_time_limit
        self.poll_seconds = poll_seconds
        self._active: dict[str, ActiveJob] = {}
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._generation = 0  # bumped when the executor is renewed
        self._killed: set[int] = set()  # generations killed on purpose (their lost tasks run again)
        self._born: dict[Future, int] = {}  # executor generation each future was submitted to
        self._stopping: dict[Future, float] = {}  # told-to-stop tasks, and when they were told
        self._finishing: dict[str, tuple[str, str | None]] = {}  # final statuses not written yet
        self._last_look = -float("inf")  # when the store was last asked for new and cancelled jobs
        self._init_feeding()

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
        if (self._wake.is_set() or now - self._last_look >= self.poll_seconds) and self.guard.ready():
            self._wake.clear()
            self._last_look = now
            self.guard.attempt(self._look_at_store)
        self._submit()
        futures = [f for a in self._active.values() for f in a.in_flight]
        if futures:
            done, _ = wait(futures, timeout=self.poll_seconds, return_when=FIRST_COMPLETED)
            for future in done:
                self._collect(future)
        else:
            self._wake.wait(self.poll_seconds)
        for active in list(self._active.values()):
            self._save(active)
            if active.job.id in self._active:  # not stopped by its key's byte quota
                self._maybe_complete(active)
        self._write_final_statuses()
        self._reap_stopping()

    def _look_at_store(self) -> None:
        self._take_up_new_jobs()
        self._drop_finished_jobs()

    def _take_up_new_jobs(self) -> None:
        for job in self.store.active():
            if job.id in self._active or job.id in self._finishing:
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
            self._active[job.id] = ActiveJob(
                job, kind, finished, deque(tasks), time.monotonic(), time.time() + self.job_time_limit
            )

    def _drop_finished_jobs(self) -> None:
        """Jobs cancelled through the API (their status is final in the store), and jobs over
        their time limit."""
        statuses = self.store.statuses(self._active)
        for job_id, active in list(self._active.items()):
            if statuses.get(job_id) not in ("queued", "running"):  # cancelled, or deleted
                self._stop_job(active)
            elif time.monotonic() - active.activated > self.job_time_limit:
                self._stop_job(active)
                self._finish(job_id, "failed", self._out_of_time(active))

    def _stop_job(self, active: ActiveJob) -> None:
        """No more tasks; the running ones are told to stop. Their points, and any the store
        has not taken yet, are dropped: a stopped job's stored points do not change."""
        self.executor.stop(active.job.id)
        for future in active.in_flight:
            if not future.cancel():
                self._stopping[future] = time.monotonic()
        del self._active[active.job.id]

    def _reap_stopping(self) -> None:
        """Forget stopped tasks that ended; kill the workers of one that would not stop."""
        for future in [f for f in self._stopping if f.done()]:
            del self._stopping[future]
            self._born.pop(future, None)
            self._forget_future(future)
        overdue = [f for f, told in self._stopping.items() if time.monotonic() - told > STOP_GRACE]
        if overdue and self.executor.kill():
            log.warning("%d stopped task(s) ran on for %.1f s: their workers were killed", len(overdue), STOP_GRACE)
            self._killed.add(self._generation)
            self._generation += 1
            for future in self._stopping:
                self._forget_future(future)
            self._stopping.clear()
        # A stop signal outlives every task that may read it: a Dask future reports itself
        # cancelled while its function still runs, so the signal is kept past the job's deadline.
        for job_id in self.executor.signalled_before(time.monotonic() - self.job_time_limit - STOP_GRACE):
            self.executor.forget(job_id)

    # --- points --------------------------------------------------------------------------
    def _save(self, active: ActiveJob) -> None:
        """Store the job's computed points (in order), each write retried until it lands."""
        while active.unsaved and self.guard.ready():
            task, points, yielded = active.unsaved[0]
            if not self.guard.attempt(self.store.add_points, active.job.id, points, active.kind.failed):
                return
            active.unsaved.popleft()
            active.finished.update(points)
            if self._over_byte_quota(active):
                return
            rest = task_remainder(active.kind, task, active.finished) if yielded else None
            if rest is not None:  # it gave its worker to another key: the rest of it runs later
                active.pending.appendleft(rest)
            active.pending.extend(
                active.kind.follow_up(active.job.spec, active.job.plan, task, active.finished, self.chunk_size)
            )

    def _over_byte_quota(self, active: ActiveJob) -> bool:
        """A job whose points took its key past the byte quota stops there, its points kept."""
        quotas = self.store.quotas
        if quotas is None:
            return False
        used = self.store.usage(active.job.owner).bytes
        if used <= quotas.max_bytes:
            return False
        self._stop_job(active)
        self._finish(
            active.job.id,
            "failed",
            f"stopped by the key's quota of stored bytes: {used} used of {quotas.max_bytes}; "
            f"{len(active.finished)} of {active.job.total} points are stored. To free space, delete "
            "jobs you no longer need (DELETE /v1/jobs/{id})",
        )
        return True

    # --- the end of a job --------------------------------------------------------------------
    def _maybe_complete(self, active: ActiveJob) -> None:
        if active.pending or active.in_flight or active.unsaved:
            return
        stored = len(active.finished)
        del self._active[active.job.id]
        if stored == active.job.total:
            self._finish(active.job.id, "succeeded")
        elif time.time() >= active.deadline:  # its tasks ended at the deadline, before the runner looked
            self._finish(active.job.id, "failed", self._out_of_time(active))
        else:
            self._finish(active.job.id, "failed", f"only {stored} of {active.job.total} points could be computed")

    def _out_of_time(self, active: ActiveJob) -> str:
        return (
            f"stopped by the job time limit of {self.job_time_limit:g} s; {len(active.finished)} of "
            f"{active.job.total} points are stored"
        )

    def _finish(self, job_id: str, status: str, error: str | None = None) -> None:
        """A job's final status, written at the end of the step (and again while the store
        cannot take it)."""
        self._finishing[job_id] = (status, error)

    def _write_final_statuses(self) -> None:
        for job_id, (status, error) in list(self._finishing.items()):
            if not self.guard.ready() or not self.guard.attempt(self.store.finish, job_id, status, error):
                return
            del self._finishing[job_id]
