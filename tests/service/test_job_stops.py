"""Every run stops when asked or out of time: a cancelled job frees its workers at once, the job
time limit ends running tasks, IPOPT stops at its next iteration, and a stopped server leaves
no worker behind."""

from __future__ import annotations

import os
import signal
import time

import pytest
from conftest import EXAMPLES, Deployment
from servers import ApiServer

from flexmech.api.client import Client

# Points that each run Newton for seconds: the gripper with exact flexures far past any
# equilibrium, 1000 iterations of a line search that keeps halving.
SLOW = {
    "example": "gripper_exact",
    "options": {"max_iterations": 1000},
    "parameters": [{"path": "/loads/actuation/force/1", "values": [1e7 + k for k in range(8)]}],
}
QUICK = {"example": "gripper", "parameters": [{"path": "/loads/actuation/force/1", "values": [0, 10, 20]}]}


def slow_point_seconds(client: Client) -> float:
    started = time.perf_counter()
    client.solve(example="gripper_exact", overrides={"/loads/actuation/force/1": 1e7}, options={"max_iterations": 1000})
    return time.perf_counter() - started


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("stops")
    server = Deployment(
        "sqlite",
        {
            "FLEXMECH_DATA_DIR": str(tmp / "data"),
            "FLEXMECH_WORKERS": "2",
            "FLEXMECH_CHUNK_SIZE": "8",
            "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
            "FLEXMECH_API_KEYS": "",
            "FLEXMECH_SOLVE_TIME_LIMIT": "60",
        },
        tmp,
    ).start()
    yield server
    server.stop()


def wait_running(client: Client, job_id: str, timeout: float = 60) -> None:
    deadline = time.monotonic() + timeout
    while client.job(job_id).status != "running":
        assert time.monotonic() < deadline
        time.sleep(0.1)


def test_cancelled_jobs_free_their_workers_at_once(server):
    with Client(server.url) as client:
        point = slow_point_seconds(client)
        # each slow point keeps a worker busy for a while (a task of 8 for 8 x that), long beside
        # the quick sweep's own time, so that 4 points below tell stopping (the point in progress
        # and the quick sweep: 0.9 s after a 1.0 s point) from waiting (about 7 points). A point
        # took 0.99-1.0 s here: the bound was once 1.0 s, and a quiet run fell under it.
        assert point > 0.5
        slow = [client.sweep(**SLOW) for _ in range(2)]  # both workers busy
        for job in slow:
            wait_running(client, job.id)
        time.sleep(1.0)
        cancelled = time.perf_counter()
        for job in slow:
            assert client.cancel(job.id).status == "cancelled"
        stored = [client.job(job.id).progress.done for job in slow]
        quick = client.sweep(**QUICK)
        final = client.wait(quick.id, timeout=120)
        freed = time.perf_counter() - cancelled
        assert final.status == "succeeded"
        # Without stopping, the quick sweep waited for the rest of both 8-point tasks (about 7
        # slow points); now for the slow point in progress at most (each task looks between
        # points), or the grace before a stubborn task's workers are killed.
        print(f"\nslow point {point:.1f} s; quick sweep done {freed:.1f} s after the cancel")
        assert freed < 4 * point
        time.sleep(1.0)
        assert [client.job(job.id).progress.done for job in slow] == stored  # nothing stored after the cancel


def test_the_job_time_limit_ends_running_tasks(tmp_path):
    """Independent of the machine's speed: the slow job's 32 points (each runs Newton for over a
    second here, longer on a slower machine) cannot end within the 10 s limit, and the quick
    sweep, about a second here, can (on a machine ten times slower too). The quick one needs the
    only worker, so it succeeds only if the slow job's task ended at its deadline."""
    server = Deployment(
        "sqlite",
        {
            "FLEXMECH_DATA_DIR": str(tmp_path / "data"),
            "FLEXMECH_WORKERS": "1",
            "FLEXMECH_CHUNK_SIZE": "8",
            "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
            "FLEXMECH_API_KEYS": "",
            "FLEXMECH_JOB_TIME_LIMIT": "10",
        },
        tmp_path,
    ).start()
    longer = {**SLOW, "parameters": [{"path": "/loads/actuation/force/1", "values": [1e7 + k for k in range(32)]}]}
    try:
        with Client(server.url) as client:
            slow = client.sweep(**longer)
            final = client.wait(slow.id, timeout=120)
            assert final.status == "failed" and "stopped by the job time limit of 10 s" in final.error
            quick = client.sweep(**QUICK)
            assert client.wait(quick.id, timeout=120).status == "succeeded"
    finally:
        server.stop()


def test_ipopt_stops_at_its_next_iteration_when_asked():
    import json

    from flexmech.models import compile_mechanism, load_document
    from flexmech.service.design.optimize import prepare, run_start
    from flexmech.service.design.problem import design_problem

    doc = load_document(json.loads((EXAMPLES / "grasper_shape.json").read_text()))
    prepared = prepare(design_problem(compile_mechanism(doc), doc.optimize))
    asked = []
    stopped = run_start(prepared, 0, stop=lambda: asked.append(1) or len(asked) > 2)
    assert stopped.status == "time_limit" and stopped.ipopt_status == "User_Requested_Stop"
    assert stopped.iterations <= 3
    assert run_start(prepared, 0).status == "optimal"  # the same solver, without a stop


def test_a_stopped_server_leaves_no_worker_behind(tmp_path):
    env = {
        "FLEXMECH_DATA_DIR": str(tmp_path / "data"),
        "FLEXMECH_WORKERS": "2",
        "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
        "FLEXMECH_API_KEYS": "",
    }
    server = ApiServer(env, tmp_path / "server.log")
    group = server.proc.pid
    with Client(server.url) as client:
        job = client.sweep(**SLOW)
        wait_running(client, job.id)
        time.sleep(2.0)  # the workers are computing
    os.kill(server.proc.pid, signal.SIGTERM)  # the server alone, as an orchestrator would
    server.proc.wait(30)
    deadline = time.monotonic() + 15
    while time.monotonic() < deadline:
        try:
            os.killpg(group, 0)  # someone in the server's process group is still alive
        except ProcessLookupError:
            break
        time.sleep(0.2)
    else:
        os.killpg(group, signal.SIGKILL)
        raise AssertionError("workers outlived the server:\n" + server.output())
    assert "leaked semaphore" not in server.output(tail=None)
    server.stop()


def test_a_cancelled_job_stops_on_a_dask_cluster_too(request, tmp_path):
    """On a cluster the stop signal is a Dask Event: tasks look between points (no killing)."""
    from conftest import make_deployment

    deployment = make_deployment("dask", request, tmp_path)
    deployment.env["FLEXMECH_CHUNK_SIZE"] = "16"
    server = deployment.start()
    slow_job = {**SLOW, "parameters": [{"path": "/loads/actuation/force/1", "values": [1e7 + k for k in range(16)]}]}
    try:
        with Client(server.url) as client:
            point = slow_point_seconds(client)
            slow = [client.sweep(**slow_job) for _ in range(2)]  # the cluster's two workers busy
            for job in slow:
                wait_running(client, job.id)
            time.sleep(1.0)
            cancelled = time.perf_counter()
            for job in slow:
                client.cancel(job.id)
            quick = client.sweep(**QUICK)
            assert client.wait(quick.id, timeout=120).status == "succeeded"
            freed = time.perf_counter() - cancelled
        # Without stopping, the quick sweep waited for the rest of two 16-point tasks (about 15
        # slow points); a task now ends after the point in progress.
        print(f"\nDask: slow point {point:.1f} s; quick sweep done {freed:.1f} s after the cancel")
        assert freed < 8 * point
    finally:
        server.stop()
