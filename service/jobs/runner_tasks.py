"""The job runner's traffic with its executor: tasks sent fairly between keys
(service.jobs.fair_share), taken back as they end, and never lost.

A task whose future comes back cancelled (the pool was killed to stop another job's task
before this one ran) or broken with a pool killed on purpose goes back to its job's queue;
one whose worker died on its own is tried once more; one that gave its worker up has its
points stored and the rest of its work queued again.
"""

from __future__ import annotations

import logging
import time
import uuid
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field

from flexmech.service.jobs.executors import TaskExecutor
from flexmech.service.jobs.failures import TaskFailed, failure_in
from flexmech.service.jobs.fair_share import shares, submission_order
from flexmech.service.jobs.kinds import JobKind, run_task
from flexmech.service.jobs.store import Job

log = logging.getLogger("flexmech.runner")

MAX_TASK_ATTEMPTS = 2  # a task whose worker died is tried once more before its job fails


@dataclass
class ActiveJob:
    job: Job
    kind: JobKind
    finished: dict[int, dict]
    pending: deque
    activated: float  # time.monotonic() when this process took the job up
    deadline: float  # time.time() by which its tasks must end (the job time limit)
    in_flight: dict[Future, dict] = field(default_factory=dict)
    attempts: dict[int, int] = field(default_factory=dict)  # id(task) -> attempts
    unsaved: deque = field(default_factory=deque)  # (task, points, yielded) whose points are not stored yet


class TaskFeeding:
    """The JobRunner's sending and taking back of tasks (a part of it: it holds the state)."""

    executor: TaskExecutor
    _active: dict[str, ActiveJob]
    _generation: int
    _killed: set[int]
    _born: dict[Future, int]

    def _init_feeding(self) -> None:
        self._task_ids: dict[Future, str] = {}  # each future's task id (its yield signal)
        self._sent_at: dict[Future, float] = {}  # time.monotonic() each was sent
        self._yielding: set[Future] = set()  # tasks asked to give their worker up

    # --- sending ---------------------------------------------------------------------------
    def _owners_with_work(self) -> dict[str, list[ActiveJob]]:
        owners: dict[str, list[ActiveJob]] = {}
        for active in self._active.values():
            if active.pending or active.in_flight:
                owners.setdefault(active.job.owner, []).append(active)
        return owners

    def _submit(self) -> None:
        """Send tasks while there is room: a lone key may fill the executor's queue; with two
        or more keys with work, each gets its share of the workers, fewest-held first, and
        keys over their share are asked to yield to a key that waits below it."""
        owners = self._owners_with_work()
        in_flight = {owner: sum(len(a.in_flight) for a in jobs) for owner, jobs in owners.items()}
        waiting = {owner: sum(len(a.pending) for a in jobs) for owner, jobs in owners.items()}
        limit = shares(self.executor.workers, self.executor.capacity, set(owners))
        room = (self.executor.capacity if len(owners) <= 1 else self.executor.workers) - sum(in_flight.values())
        progressed = True
        while room > 0 and progressed:
            progressed = False
            for owner in submission_order(in_flight, waiting):
                if room <= 0 or in_flight[owner] >= limit[owner]:
                    continue
                active = min((a for a in owners[owner] if a.pending), key=lambda a: len(a.in_flight))
                if not self._send(active):
                    return
                in_flight[owner] += 1
                waiting[owner] -= 1
                room -= 1
                progressed = True
        self._ask_to_yield(owners, in_flight, waiting, limit)

    def _send(self, active: ActiveJob) -> bool:
        task, task_id = active.pending[0], uuid.uuid4().hex
        control = {**self.executor.control_for(active.job.id), **self.executor.yield_signal_for(task_id)}
        sent = {**task, "deadline": active.deadline, "control": control}
        try:
            future = self.executor.executor().submit(run_task, active.job.kind, active.job.spec, sent)
        except BrokenProcessPool:  # a worker died since the last look: new pool, same task
            self._renew_executor()
            return False
        active.pending.popleft()
        active.in_flight[future] = task
        self._born[future] = self._generation
        self._task_ids[future] = task_id
        self._sent_at[future] = time.monotonic()
        return True

    def _ask_to_yield(
        self, owners: dict[str, list[ActiveJob]], in_flight: dict, waiting: dict, limit: dict[str, int]
    ) -> None:
        """While a key waits below its share, every key over its share gives up its newest
        tasks beyond it (queued ones first: they would run before the waiting key's)."""
        if not any(waiting[owner] > 0 and in_flight[owner] < limit[owner] for owner in owners):
            return
        for owner, jobs in owners.items():
            futures = sorted((f for a in jobs for f in a.in_flight), key=self._sent_at.__getitem__, reverse=True)
            asked = sum(1 for f in futures if f in self._yielding)
            for future in [f for f in futures if f not in self._yielding][: in_flight[owner] - limit[owner] - asked]:
                self.executor.ask_to_yield(self._task_ids[future])
                self._yielding.add(future)

    # --- taking back -------------------------------------------------------------------------
    def _collect(self, future: Future) -> None:
        owner = next((a for a in self._active.values() if future in a.in_flight), None)
        yielded = future in self._yielding
        task_id = self._task_ids.get(future, "")
        try:
            if owner is not None:
                self._take_back(owner, future, yielded, task_id)
        finally:
            self._forget_future(future)

    def _take_back(self, owner: ActiveJob, future: Future, yielded: bool, task_id: str) -> None:
        task = owner.in_flight.pop(future)
        born = self._born.pop(future, self._generation)
        if future.cancelled():  # the pool was killed (another job's task would not stop) before it ran
            owner.pending.appendleft(task)
            return
        error = future.exception() or failure_in(future.result())
        if error is not None:
            self._task_failed(owner, task, error, born, task_id)
            return
        owner.unsaved.append((task, future.result(), yielded))
        self._save(owner)

    def _forget_future(self, future: Future) -> None:
        task_id = self._task_ids.pop(future, None)
        self._sent_at.pop(future, None)
        if task_id is not None:
            self.executor.task_ended(task_id)
        if future in self._yielding:
            self._yielding.discard(future)
            if task_id is not None:
                self.executor.forget_task(task_id)

    def _task_failed(self, active: ActiveJob, task: dict, error: BaseException, born: int, task_id: str) -> None:
        """A task's own error fails its job; a task lost with a broken pool runs again (charged
        an attempt only when its own worker died under it)."""
        if isinstance(error, BrokenProcessPool):
            innocent = born in self._killed or not self.executor.died_running(task_id)
            if born == self._generation:  # the first to notice renews the pool, for every job
                self._renew_executor()
            if innocent:  # killed on purpose, or stopped because another worker died
                active.pending.appendleft(task)
                return
            key = id(task)
            active.attempts[key] = active.attempts.get(key, 0) + 1
            log.warning("job %s: the worker running its task died (attempt %d)", active.job.id, active.attempts[key])
            if active.attempts[key] < MAX_TASK_ATTEMPTS:
                active.pending.appendleft(task)
                return
        log.error("job %s: task failed: %s", active.job.id, error)
        said = str(error) if isinstance(error, TaskFailed) else f"{type(error).__name__}: {error}"
        self._stop_job(active)
        self._finish(active.job.id, "failed", f"a task failed: {said}")

    def _renew_executor(self) -> None:
        self.executor.renew()
        self._generation += 1

    # provided by JobRunner (declared here for the type checker; the runner defines them)
    _save: Callable[[ActiveJob], None]
    _stop_job: Callable[[ActiveJob], None]
    _finish: Callable[..., None]
