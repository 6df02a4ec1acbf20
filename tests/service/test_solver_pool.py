"""The server's solver workers (api.solver_pool): errors come back as the types the API answers
with, a call past its time limit ends its worker (no survivor) and a new one serves the next,
small calls are not held behind large ones, and over HTTP a small solve answers while a long
simulation runs."""

from __future__ import annotations

import asyncio
import json
import os
import re
import time

import httpx
import pytest

from flexmech.api.errors import ApiError
from flexmech.api.solver_pool import WORKER_NAME, SolverPool
from flexmech.models import MechanismError
from flexmech.models.documents.reading import parse_json


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a killed child not yet reaped is a zombie: it runs nothing
    with open(f"/proc/{pid}/stat") as stat:
        return stat.read().split(") ", 1)[1][0] != "Z"


def _run(coroutine):
    return asyncio.run(coroutine)


def test_errors_cross_to_the_server_as_their_own_types():
    async def scenario():
        pool = SolverPool(1)
        try:
            with pytest.raises(MechanismError) as mechanism:
                await pool.call(parse_json, b'{"a": 1, "a": 2}', "the body")
            with pytest.raises(ValueError, match="invalid literal for int"):
                await pool.call(int, "seven")
            return mechanism.value, await pool.call(sum, [1, 2, 3])
        finally:
            pool.close()

    error, after = _run(scenario())
    assert (error.pointer, error.problem) == ("", "the body is not valid JSON: duplicate key 'a' in one object")
    assert after == 6  # the worker survives a failed call


def test_a_call_past_its_time_limit_ends_its_worker_and_a_new_one_serves():
    async def scenario():
        pool = SolverPool(1, build_allowance=0.0)
        try:
            first = pool.pids[0]
            assert await pool.call(os.getpid) == first
            with pytest.raises(ApiError) as late:
                await pool.call(time.sleep, 600, time_limit=0.2)
            return first, late.value, await pool.call(os.getpid), pool.pids[0]
        finally:
            pool.close()

    first, late, serving, listed = _run(scenario())
    assert (late.status, late.code) == (503, "time_limit")
    assert late.message == (
        "the work did not end within 1.2 s (its time limit of 0.2 s, 0 s of building and 1 s of grace) and was stopped"
    )
    assert not _alive(first)
    assert serving == listed != first


def _a_loop_that_hangs(limit: float) -> None:
    from flexmech.service.deadline import ends_after

    ends_after(limit)  # a solving loop starts the call's clock, then never checks it
    time.sleep(600)


def test_a_worker_past_its_loops_deadline_is_replaced_without_the_build_allowance():
    """Once a call's first loop has started its clock (service.deadline), the worker is
    replaced one second past that deadline: the minute of build allowance no longer applies."""

    async def scenario():
        pool = SolverPool(1, build_allowance=60.0)
        try:
            first = pool.pids[0]
            with pytest.raises(ApiError) as late:
                await pool.call(_a_loop_that_hangs, 0.3, time_limit=10.0)
            return first, late.value, await pool.call(os.getpid)
        finally:
            pool.close()

    first, late, serving = _run(scenario())
    assert (late.status, late.code) == (503, "time_limit")
    assert re.fullmatch(
        r"the work did not end within 1 s past its deadline, [0-9.]+ s after the call started "
        r"\(its time limit of 10 s\) and was stopped",
        late.message,
    ), late.message
    assert not _alive(first) and serving != first


def test_loops_of_one_call_share_the_first_deadline():
    from multiprocessing import Value

    from flexmech.service.deadline import call_scope, ends_after

    shared = Value("d", 0.0, lock=False)
    outside = ends_after(5.0)
    with call_scope(shared):
        first = ends_after(5.0)
        assert shared.value == first
        time.sleep(0.01)
        assert ends_after(5.0) == first  # a later loop: the call's deadline, not its own
        shorter = ends_after(1.0)
        assert shorter < first and shared.value == shorter  # a shorter limit moves it earlier
        assert ends_after(None) == float("inf")
    assert shared.value == 0.0
    time.sleep(0.01)
    assert ends_after(5.0) > outside  # outside a call, every loop has its own


def test_a_call_whose_caller_went_away_keeps_its_worker_until_its_work_ends():
    """A cancelled call (a client that disconnected) does not kill its worker (its caches stay
    warm): the next call waits for the work to end and runs on the same process."""

    async def scenario():
        pool = SolverPool(1)
        try:
            first = await pool.call(os.getpid)
            abandoned = asyncio.ensure_future(pool.call(time.sleep, 1.0))
            await asyncio.sleep(0.3)
            abandoned.cancel()
            return first, await pool.call(os.getpid), abandoned.cancelled()
        finally:
            pool.close()

    first, after, cancelled = _run(scenario())
    assert cancelled and after == first


def test_a_small_call_is_not_held_behind_large_ones():
    """Two workers: both large calls may not take worker 0, so the second waits while a small
    call passes both."""

    async def scenario():
        pool = SolverPool(2)
        try:
            await asyncio.gather(pool.call(os.getpid), pool.call(os.getpid))  # both started
            long_one = asyncio.ensure_future(pool.call(time.sleep, 1.5, large=True))
            queued = asyncio.ensure_future(pool.call(os.getpid, large=True))
            await asyncio.sleep(0.2)
            small = await pool.call(os.getpid)
            state = (long_one.done(), queued.done())
            large_pid = await queued
            await long_one
            return pool.pids, small, state, large_pid
        finally:
            pool.close()

    pids, small, (long_done, queued_done), large_pid = _run(scenario())
    assert small == pids[0] and large_pid == pids[1]
    assert not long_done and not queued_done  # the small call answered while both large ones waited or ran


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """A server with two solver workers (the second starts with the first long request) and a
    3 s solve time limit."""
    from conftest import EXAMPLES
    from servers import ApiServer

    tmp = tmp_path_factory.mktemp("solvers")
    server = ApiServer(
        {
            "FLEXMECH_DATA_DIR": str(tmp / "data"),
            "FLEXMECH_WORKERS": "1",
            "FLEXMECH_SOLVER_WORKERS": "2",
            "FLEXMECH_SOLVE_TIME_LIMIT": "3",
            "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
            "FLEXMECH_API_KEYS": "",
        },
        tmp / "server.log",
    )
    yield server
    server.stop()


def test_small_solves_answer_while_a_long_simulation_runs(server):
    """Over HTTP: a simulation through /v1/solve runs to the 3 s limit on one worker; gripper
    solves sent meanwhile are answered before it ends, and it ends with status time_limit."""
    from conftest import EXAMPLES

    document = json.loads((EXAMPLES / "rod_free_vibration.json").read_text())
    document["elements"]["rod"]["intervals"] = 64
    rod = {
        "document": document,
        "analysis": "simulate",
        "simulate": {"until": 2, "step": 1e-4},
    }  # 20000 steps (the most /v1/solve runs) of 64 elements: 15 s and more, however the kernels run
    # (8 elements once finished within the limit, in 2.3 s, on compiled kernels)
    gripper = {"example": "gripper", "overrides": {"/loads/actuation/force/1": 50}}
    with httpx.Client(base_url=server.url, timeout=120) as client:
        client.post("/v1/solve", json=gripper).raise_for_status()  # a warm worker 0

    async def scenario():
        async with httpx.AsyncClient(base_url=server.url, timeout=120) as client:
            long_run = asyncio.ensure_future(client.post("/v1/solve", json=rod))
            await asyncio.sleep(1.0)
            answers = [await client.post("/v1/solve", json=gripper) for _ in range(5)]
            running = not long_run.done()
            return answers, running, await long_run

    answers, running, long_answer = _run(scenario())
    assert all(a.status_code == 200 and a.json()["status"] == "converged" for a in answers)
    assert running, long_answer.text[:300]  # the small solves did not wait for it
    assert long_answer.status_code == 200 and long_answer.json()["status"] == "time_limit", long_answer.text[:300]


def _parent_of(pid: int) -> int:
    with open(f"/proc/{pid}/stat") as stat:
        return int(stat.read().rsplit(")", 1)[1].split()[1])


def _solver_workers(ancestor: int, names: tuple[bytes, ...] = (WORKER_NAME,)) -> list[int]:
    """The processes named as solver workers (or other `names`) that descend from `ancestor`
    (the fork server between them)."""
    found = []
    for entry in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{entry}/comm", "rb") as comm:
                if comm.read().strip() not in names:
                    continue
            pid = int(entry)
            for _ in range(4):
                pid = _parent_of(pid)
                if pid == ancestor:
                    found.append(int(entry))
                    break
        except (OSError, ValueError, IndexError):
            continue
    return found


def test_a_killed_server_leaves_no_solver_worker(server):
    """kill -9 of the server process alone (not its group): its workers, and the process that
    parses large bodies, end with it."""
    import signal

    from flexmech.api.body_parsing import LARGE_BODY, PARSER_NAME

    large = {
        "example": "gripper",
        "overrides": {"/loads/actuation/force/1": 50.0},
        "pad": ["x" * 100] * (LARGE_BODY // 90),
    }
    assert httpx.post(server.url + "/v1/solve", json=large, timeout=60).status_code == 422  # parsed, then refused
    workers = _solver_workers(server.proc.pid, (WORKER_NAME, PARSER_NAME))
    assert len(_solver_workers(server.proc.pid, (PARSER_NAME,))) == 1
    assert workers and all(_alive(pid) for pid in workers), workers
    os.kill(server.proc.pid, signal.SIGKILL)
    server.proc.wait(10)
    deadline = time.monotonic() + 10
    while any(_alive(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not [pid for pid in workers if _alive(pid)]


def test_ending_a_job_pool_spares_the_other_children_of_the_server():
    """A job pool that is killed (a stopped job ran on) ends its own workers only: the server's
    solver workers are its children too (they once died with it, failing their requests)."""
    import multiprocessing

    from flexmech.service.jobs.executors import ProcessPool

    bystander = multiprocessing.get_context("spawn").Process(target=time.sleep, args=(60,), name="bystander")
    bystander.start()
    pool = ProcessPool(1)
    try:
        job_worker = pool.executor().submit(os.getpid).result(timeout=60)
        pool.kill()
        assert not _alive(job_worker)
        assert bystander.is_alive()
    finally:
        pool.close()
        bystander.kill()
        bystander.join(5)
