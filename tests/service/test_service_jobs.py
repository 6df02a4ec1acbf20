"""Jobs through a real server: sweeps for each way to deploy it (SQLite with a process pool,
PostgreSQL with a process pool, PostgreSQL with a Dask cluster: scheduler + two workers),
and seed 004's impact study on the Dask cluster."""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import ACTUATION, EXAMPLES

from flexmech.api.client import Client
from flexmech.models import compile_mechanism, load_document
from flexmech.service import sweep

LOAD_PATH = {"path": ACTUATION, "start": -60.0, "stop": 60.0, "steps": 199}  # 200 points


def _wait_until(condition, timeout: float, what: str):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.01)
    raise AssertionError(f"timed out waiting for {what}")


def test_200_point_sweep_job_progress_and_result(deployment):
    server = deployment.start()
    try:
        with Client(server.url) as client:
            health = client.health()
            assert health.database == ("sqlite" if deployment.name == "sqlite" else "postgresql")
            assert health.executor.startswith("Dask cluster" if deployment.name == "dask" else "process pool")
            job = client.sweep(
                example="gripper",
                parameters=[LOAD_PATH],
                continuation=ACTUATION,
                outputs=["end_effector.x", "end_effector.y", "anchor.Fx"],
            )
            assert job.status == "queued" and job.progress.total == 200
            seen = []
            final = client.wait(job.id, timeout=180, poll=0.01, progress=seen.append)
            assert final.status == "succeeded", final.error
            done = [s.progress.done for s in seen]
            assert done == sorted(done) and done[-1] == 200
            assert any(0 < d < 200 for d in done), f"no progress seen between 0 and 200: {done}"
            assert final.timings.started_at and final.timings.finished_at and final.timings.elapsed_seconds > 0
            result = client.result(job.id)
    finally:
        server.stop()
    assert result.complete and result.status == "succeeded"
    points = result.result.points
    assert [p.index for p in points] == list(range(200))
    assert all(p.status == "converged" for p in points)
    assert result.result.output_units == {"end_effector.x": "mm", "end_effector.y": "mm", "anchor.Fx": "uN"}
    # the same load path solved by the core's sweep
    mech = compile_mechanism(load_document(EXAMPLES / "gripper.json"))
    core = sweep(mech, ACTUATION, np.linspace(-60, 60, 200))
    x = np.array([p.outputs["end_effector.x"] for p in points])
    np.testing.assert_allclose(x, core.outputs["end_effector.x"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose([p.values[0] for p in points], np.linspace(-60, 60, 200), rtol=1e-15)


def test_independent_points_over_a_cartesian_grid(deployment):
    server = deployment.start()
    try:
        with Client(server.url) as client:
            job = client.sweep(
                example="gripper",
                outputs=["end_effector.x"],
                parameters=[
                    {"path": ACTUATION, "values": [-20, 0, 20, 40]},
                    {"path": "/sections/flexure/h", "values": [0.004, 0.005, 0.006]},
                ],
            )
            assert client.wait(job.id, timeout=180).status == "succeeded"
            points = client.result(job.id).result.points
    finally:
        server.stop()
    assert len(points) == 12
    base = compile_mechanism(load_document(EXAMPLES / "gripper.json"))
    from flexmech.service import solve_equilibrium

    for p in points:
        force, h = p.values
        assert (force, h) == ([-20, 0, 20, 40][p.index // 3], [0.004, 0.005, 0.006][p.index % 3])
        core = solve_equilibrium(base.with_values({ACTUATION: force, "/sections/flexure/h": h}))
        assert p.outputs["end_effector.x"] == pytest.approx(core.outputs()["end_effector.x"], rel=1e-9, abs=1e-12)


def test_cancel_a_running_job(deployment):
    server = deployment.start()
    try:
        with Client(server.url) as client:
            job = client.sweep(
                example="gripper",
                continuation=ACTUATION,
                outputs=["end_effector.x"],
                parameters=[{"path": ACTUATION, "start": -60, "stop": 60, "steps": 19_999}],
            )
            _wait_until(lambda: client.job(job.id).progress.done > 0, 120, "the first points")
            cancelled = client.cancel(job.id)
            assert cancelled.status == "cancelled" and cancelled.error == "cancelled by the caller"
            time.sleep(1.0)  # the runner sees the cancel at its next look; nothing is stored after
            settled = client.job(job.id).progress.done
            time.sleep(1.0)
            after = client.job(job.id)
            result = client.result(job.id)
    finally:
        server.stop()
    assert after.status == "cancelled" and after.progress.done == settled < 20_000
    assert not result.complete and len(result.result.points) == settled


def test_killed_server_resumes_the_job_and_keeps_every_finished_point(deployment):
    """SIGKILL the server (and its worker processes) in the middle of a load path; a new server
    on the same store finishes the job. Points stored before the kill come back untouched (their
    own solve timings included, so none was recomputed), and every point equals an
    uninterrupted run to the last bit."""
    spec_path = {"path": ACTUATION, "start": -60.0, "stop": 60.0, "steps": 1499}
    server = deployment.start(FLEXMECH_CHUNK_SIZE="2")
    with Client(server.url) as client:
        job = client.sweep(
            example="gripper",
            parameters=[spec_path],
            continuation=ACTUATION,
            outputs=["end_effector.x", "end_effector.y"],
        )
        _wait_until(lambda: client.job(job.id).progress.done >= 100, 120, "100 points")
        before = client.result(job.id)
        server.kill()
    assert not before.complete and 100 <= len(before.result.points) < 1500

    server = deployment.start()
    try:
        with Client(server.url) as client:
            final = client.wait(job.id, timeout=300)
            result = client.result(job.id)
    finally:
        server.stop()
    assert final.status == "succeeded" and final.restarts == 1
    assert result.complete
    after = {p.index: p for p in result.result.points}
    assert sorted(after) == list(range(1500))
    for p in before.result.points:
        assert after[p.index] == p

    spec = {
        "document": json.loads((EXAMPLES / "gripper.json").read_text()),
        "parameters": [spec_path],
        "continuation": ACTUATION,
        "outputs": ["end_effector.x", "end_effector.y"],
    }
    uninterrupted = _sweep_in_a_fresh_process(spec, list(range(1500)))
    for i, p in after.items():
        assert p.outputs == uninterrupted[i]["outputs"]
        assert p.iterations == uninterrupted[i]["iterations"]


def _sweep_in_a_fresh_process(spec: dict, indices: list[int]) -> dict[int, dict]:
    """The sweep job's points computed by a new Python process, as the job's workers are: "to
    the last bit" holds between processes that start alike, not with this one, which has run
    hundreds of tests (its first gripper point once differed in the 16th digit)."""
    import subprocess
    import sys

    script = (
        "import json, sys; from flexmech.service.jobs.kinds import kind_named; spec = json.load(sys.stdin); "
        "points = kind_named('sweep').run(spec, {'indices': spec.pop('indices'), 'guess': None, 'line': 0}); "
        "json.dump([[i, p] for i, p in points], sys.stdout)"
    )
    done = subprocess.run(
        [sys.executable, "-c", script],
        input=json.dumps({**spec, "indices": indices}),
        capture_output=True,
        text=True,
        check=True,
        timeout=600,
    )
    return {i: p for i, p in json.loads(done.stdout)}


def _pool_workers(server_pid: int) -> list[int]:
    """Process-pool workers of the server: its children started by multiprocessing's spawn, but
    its solver workers (api.solver_pool names them)."""
    from flexmech.api.solver_pool import WORKER_NAME

    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            ppid = int(stat.read_text().rsplit(")", 1)[1].split()[1])
            cmdline = (stat.parent / "cmdline").read_bytes()
            name = (stat.parent / "comm").read_bytes().strip()
        except (OSError, ValueError, IndexError):
            continue
        if ppid == server_pid and b"spawn_main" in cmdline and name != WORKER_NAME:
            found.append(int(stat.parent.name))
    return found


def test_a_dead_pool_worker_does_not_lose_the_job(tmp_path, request):
    """SIGKILL one process-pool worker mid-job: the pool is replaced, the tasks it held are sent
    again, and the job completes with every point."""
    from conftest import make_deployment

    server = make_deployment("sqlite", request, tmp_path).start(FLEXMECH_CHUNK_SIZE="2")
    try:
        with Client(server.url) as client:
            job = client.sweep(
                example="gripper",
                outputs=["end_effector.x"],
                parameters=[{"path": ACTUATION, "start": -60, "stop": 60, "steps": 999}],
            )
            _wait_until(lambda: client.job(job.id).progress.done >= 50, 120, "50 points")
            workers = _pool_workers(server.proc.pid)
            assert workers, "no pool worker found"
            os.kill(workers[0], signal.SIGKILL)
            final = client.wait(job.id, timeout=300)
            result = client.result(job.id)
    finally:
        server.stop()
    assert final.status == "succeeded", final.error
    assert result.complete and [p.index for p in result.result.points] == list(range(1000))
    assert all(p.status == "converged" for p in result.result.points)
    assert "process pool broke; starting a new one" in server.output(tail=None)


def test_seed_004s_study_runs_on_dask_with_contact_laws_among_its_factors(request, tmp_path):
    """Section 7's parametric study as a job on a Dask cluster, its factors fields of the one
    `contacts` section (a law's restitution, a site's radius)."""
    from conftest import make_deployment

    deployment = make_deployment("dask", request, tmp_path)
    restitution, radius = "/contacts/pairs/conjugate/normal/restitution", "/contacts/sites/pin/radius"
    server = deployment.start()
    try:
        with Client(server.url) as client:
            assert client.health().executor.startswith("Dask cluster")
            job = client.impact_study(
                example="csfh",
                simulate={"until": 0.2},
                study={"fields": [{"path": restitution, "step": 0.05}, {"path": radius, "step": 0.001}]},
            )
            final = client.wait(job.id, timeout=300)
            assert final.status == "succeeded", final.error
            result = client.result(job.id).result
    finally:
        server.stop()
    departure = {
        (path, side): result["fields"][path][side]["influence"]["hinge.y"]["departure"]
        for path in (restitution, radius)
        for side in "+-"
    }
    # the clearance moves the first contact (0.0717 s): the runs part there; the restitution
    # acts through the rebound alone, so they part well after it
    assert max(departure[radius, side] for side in "+-") < 0.08
    assert min(departure[restitution, side] for side in "+-") > 0.1
    assert result["ranking"][0]["path"] == radius
