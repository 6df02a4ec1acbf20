"""Job workers shared fairly between keys and no task ever lost (issue 53): a key's long jobs
yield a worker to another key's sweep, and a cancel that kills the pool under another key's
queued task sends that task again."""

from __future__ import annotations

import json
import time
from collections import deque
from concurrent.futures import Future

import pytest
from conftest import ACTUATION, EXAMPLES, make_deployment

from flexmech.api.client import Client
from flexmech.service.jobs.base import task_remainder
from flexmech.service.jobs.contact import CONTACT
from flexmech.service.jobs.executors import TaskExecutor
from flexmech.service.jobs.runner import JobRunner
from flexmech.service.jobs.runner_tasks import ActiveJob
from flexmech.service.jobs.store import JobStore
from flexmech.service.jobs.sweep import SWEEP

KEYS = ("fair-first-key-0123", "fair-second-key-0123")
# each point runs Newton for about a second (test_job_stops' slow points); 64 to a task
SLOW = {
    "example": "gripper_exact",
    "options": {"max_iterations": 1000},
    "parameters": [{"path": ACTUATION, "values": [1e7 + k for k in range(64)]}],
}
QUICK = {
    "example": "gripper",
    "outputs": ["end_effector.x"],
    "parameters": [{"path": ACTUATION, "start": 0, "stop": 60, "steps": 99}],
}


class IdleExecutor(TaskExecutor):
    """An executor that runs nothing: the runner's bookkeeping on its own."""

    description, workers, capacity = "idle", 2, 4

    def executor(self):
        raise AssertionError("nothing is sent in these tests")

    def control_for(self, job_id):
        return {}

    def yield_signal_for(self, task_id):
        return {}

    def ask_to_yield(self, task_id):
        pass

    def forget_task(self, task_id):
        pass

    def close(self):
        pass


def test_a_task_cancelled_by_a_pool_kill_goes_back_to_its_job(tmp_path):
    """The bug of issue 53: the pool killed to stop one job cancels another job's queued task;
    its future comes back cancelled and the task must run again, not vanish."""
    store = JobStore(f"sqlite:///{tmp_path / 'jobs.db'}")
    job = store.create("sweep", "b", {}, {}, 4)
    runner = JobRunner(store, IdleExecutor())
    active = ActiveJob(job, SWEEP, {}, deque(), time.monotonic(), time.time() + 60)
    runner._active[job.id] = active
    lost, task = Future(), {"indices": [0, 1, 2, 3], "guess": None}
    active.in_flight[lost] = task
    assert lost.cancel()
    runner._collect(lost)
    assert list(active.pending) == [task] and not active.in_flight
    store.close()


def test_what_a_yielding_task_leaves_is_its_unfinished_points_or_the_next_chunk():
    done = {4: {}, 5: {}}
    independent = {"indices": [4, 5, 6, 7], "values": [[4.0], [5.0], [6.0], [7.0]], "guess": None}
    assert task_remainder(SWEEP, independent, done) == {"indices": [6, 7], "values": [[6.0], [7.0]], "guess": None}
    assert task_remainder(SWEEP, {"indices": [4, 5], "values": [[4.0], [5.0]]}, done) is None
    assert task_remainder(SWEEP, dict(independent, line=0), done) is None  # follow_up goes on along the path
    assert task_remainder(CONTACT, {"indices": [4, 5, 6]}, done) is None  # a contact path: in order too


def _points(client: Client, job_id: str) -> list[int]:
    return [p.index for p in client.result(job_id).result.points]


def test_another_keys_sweep_finishes_while_one_key_holds_both_workers_with_long_jobs(request, tmp_path):
    """Key A's two sweeps of 64 one-second points hold both workers in one task each; key B's
    100-point sweep (half a second of work) runs as soon as one of A's tasks yields after the
    point in progress, and finishes while both of A's jobs still run; A loses no point."""
    server = make_deployment("sqlite", request, tmp_path).start(
        FLEXMECH_API_KEYS=",".join(KEYS), FLEXMECH_CHUNK_SIZE="64", FLEXMECH_SOLVE_TIME_LIMIT="60"
    )
    try:
        with Client(server.url, api_key=KEYS[0]) as first, Client(server.url, api_key=KEYS[1]) as second:
            slow = [first.sweep(**SLOW) for _ in range(2)]
            while not all(first.job(job.id).status == "running" for job in slow):
                time.sleep(0.1)
            time.sleep(2.0)  # both tasks well into their points (a task's points are stored when it ends)
            started = time.perf_counter()
            quick = second.wait(second.sweep(**QUICK).id, timeout=300)
            took = time.perf_counter() - started
            states = [first.job(job.id) for job in slow]
            for job in slow:
                first.cancel(job.id)
            stored = [_points(first, job.id) for job in slow]
    finally:
        server.stop()
    print(f"\nkey B's 100-point sweep took {took:.1f} s beside key A's two 64-second tasks")
    assert quick.status == "succeeded" and quick.progress.done == 100
    assert all(state.status == "running" and state.progress.done < 64 for state in states), states
    assert all(indices == sorted(set(indices)) for indices in stored)


@pytest.mark.parametrize("backend", ["sqlite", "postgresql"])
def test_cancelling_one_keys_jobs_leaves_another_keys_sweep_whole(backend, request, tmp_path):
    """Issue 53's sequence: key A's two slow jobs hold both workers, key B posts a 100-point
    sweep, key A cancels its jobs: B's sweep succeeds with its 100 points, each once."""
    server = make_deployment(backend, request, tmp_path).start(
        FLEXMECH_API_KEYS=",".join(KEYS), FLEXMECH_CHUNK_SIZE="8", FLEXMECH_SOLVE_TIME_LIMIT="60"
    )
    try:
        with Client(server.url, api_key=KEYS[0]) as first, Client(server.url, api_key=KEYS[1]) as second:
            slow = [first.sweep(**SLOW) for _ in range(2)]
            while not all(first.job(job.id).status == "running" for job in slow):
                time.sleep(0.1)
            quick = second.sweep(**dict(QUICK, example="gripper_exact"))  # some seconds of work
            while second.job(quick.id).progress.done == 0:
                time.sleep(0.05)
            at_cancel = second.job(quick.id).progress.done
            cancelled = time.perf_counter()
            for job in slow:
                first.cancel(job.id)
            final = second.wait(quick.id, timeout=300)
            took = time.perf_counter() - cancelled
            indices = _points(second, quick.id)
    finally:
        server.stop()
    print(f"\n{backend}: key B's sweep ({at_cancel} points at the cancel) done {took:.1f} s after it")
    assert final.status == "succeeded", final.error
    assert indices == list(range(100))


def _rod_simulation(until: float) -> dict:
    """An analysis job of one task: the rod of 64 elements simulated `until` s in 1e-4 s steps
    (0.8 s: 8000 steps, about 5 s of stepping here: far longer than the sweep beside it)."""
    document = json.loads((EXAMPLES / "rod_free_vibration.json").read_text())
    document["elements"]["rod"]["intervals"] = 64
    return {"document": document, "analysis": "simulate", "simulate": {"until": until, "step": 1e-4, "every": 100}}


def test_a_running_one_task_job_yields_to_another_keys_sweep_and_runs_again_whole(request, tmp_path):
    """Key A's two analysis jobs (one task each, which cannot be kept in part) hold both workers;
    key B's sweep takes the worker of A's newer job, which stops at once and runs again from its
    start afterwards: B's sweep succeeds before either of A's jobs, and both of A's succeed whole."""
    server = make_deployment("sqlite", request, tmp_path).start(FLEXMECH_API_KEYS=",".join(KEYS))
    try:
        with Client(server.url, api_key=KEYS[0]) as first, Client(server.url, api_key=KEYS[1]) as second:
            long = [first.jobs.analysis(**_rod_simulation(0.8)) for _ in range(2)]
            while not all(first.job(job.id).status == "running" for job in long):
                time.sleep(0.1)
            time.sleep(1.0)
            started = time.perf_counter()
            quick = second.wait(second.sweep(**QUICK).id, timeout=300)
            took = time.perf_counter() - started
            beside = [first.job(job.id).status for job in long]
            finals = [first.wait(job.id, timeout=300) for job in long]
            reports = [first.result(job.id).result["report"] for job in long]
    finally:
        server.stop()
    stepping = ", ".join(f"{report['seconds']:.1f} s" for report in reports)
    print(f"\nkey B's sweep took {took:.1f} s beside key A's two analysis jobs ({stepping} of stepping)")
    assert quick.status == "succeeded" and quick.progress.done == 100
    assert beside == ["running", "running"]  # B did not wait for one of A's jobs to end
    assert [final.status for final in finals] == ["succeeded"] * 2, [final.error for final in finals]
    assert [report["status"] for report in reports] == ["finished"] * 2
    assert [(report["time_reached"], report["steps"]) for report in reports] == [(0.8, 8000)] * 2
    assert reports[0]["outputs"] == reports[1]["outputs"]  # the one that yielded ran again whole
