"""The job store failing under a running job: an SQLite file locked for 15 s, and a data folder
that fills up (a small tmpfs). Points computed meanwhile are kept and written when the store
comes back: every point is stored exactly once, the job succeeds, and requests that need the
store are answered 503 meanwhile, not 500."""

from __future__ import annotations

import json
import sqlite3
import subprocess
import time
from pathlib import Path

import httpx
from conftest import EXAMPLES, Deployment

from flexmech.api.client import Client

ACTUATION = "/loads/actuation/force/1"


def sweep_of(points: int, example: str, outputs: list[str] | None) -> dict:
    body = {
        "example": example,
        "parameters": [{"path": ACTUATION, "values": [k * 80.0 / points for k in range(points)]}],
    }
    return body | ({"outputs": outputs} if outputs else {})


def stored_indices(database: Path, job_id: str) -> list[int]:
    with sqlite3.connect(database) as connection:
        return [
            i
            for (i,) in connection.execute(
                'SELECT "index" FROM flexmech_job_points WHERE job_id = ? ORDER BY "index"', (job_id,)
            )
        ]


def wait_for(predicate, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, what
        time.sleep(0.2)


def server_on(data: Path, tmp: Path):
    return Deployment(
        "sqlite",
        {
            "FLEXMECH_DATA_DIR": str(data),
            "FLEXMECH_WORKERS": "2",
            "FLEXMECH_CHUNK_SIZE": "4",
            "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
            "FLEXMECH_API_KEYS": "",
        },
        tmp,
    ).start()


def test_a_store_locked_for_15_s_loses_no_point(tmp_path):
    server = server_on(tmp_path / "data", tmp_path)
    database = tmp_path / "data" / "flexmech.db"
    try:
        with Client(server.url, timeout=120) as client:
            job = client.sweep(**sweep_of(1000, "gripper_exact", ["end_effector.x"]))
            wait_for(lambda: client.job(job.id).progress.done >= 40, 120, "the job never got going")
            lock = sqlite3.connect(database, timeout=60, isolation_level=None)
            lock.execute("BEGIN EXCLUSIVE")  # every writer waits 1.5 s, then fails: for 15 s, retried
            locked_at = client.job(job.id).progress.done
            started = time.monotonic()
            # a new job is refused (the lock wait is 1.5 s; it was 30 s, past this generous timeout)
            refused = httpx.post(server.url + "/v1/sweeps", json=sweep_of(10, "gripper", None), timeout=25)
            assert refused.status_code == 503 and refused.json()["error"]["code"] == "store_unavailable"
            assert int(refused.headers["retry-after"]) > 0
            time.sleep(max(15 - (time.monotonic() - started), 0))
            assert client.job(job.id).progress.done == locked_at  # nothing could be written
            lock.execute("COMMIT")
            lock.close()
            final = client.wait(job.id, timeout=300)
        assert final.status == "succeeded" and final.progress.done == 1000
        assert stored_indices(database, job.id) == list(range(1000))  # every point, exactly once
        log = server.output(tail=None)
        assert "job store unavailable, retrying with backoff" in log and "job store back after" in log
        assert "Traceback" not in log
    finally:
        server.stop()


def _mount_small_tmpfs(folder: Path) -> bool:
    folder.mkdir()
    return (
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=3m", "tmpfs", str(folder)], capture_output=True).returncode
        == 0
    )


def test_a_full_data_folder_loses_no_point(tmp_path):
    disk = tmp_path / "disk"
    if not _mount_small_tmpfs(disk):  # no mount here (not root): a store that fails on purpose instead
        return _store_failing_on_purpose(tmp_path)
    server = server_on(disk / "data", tmp_path)
    try:
        with Client(server.url, timeout=120) as client:
            job = client.sweep(**sweep_of(3000, "gripper", None))  # every output: about 6 MB of points

            def stalled() -> bool:
                # the disk is full once the store says so (progress that merely paused for two
                # seconds on a loaded machine once passed for it); it had made progress first
                done = client.job(job.id).progress.done
                return 0 < done < 3000 and "job store unavailable" in server.output(tail=None)

            wait_for(stalled, 180, "the disk never filled")
            # A new job is refused while the store cannot write. The full disk is not steady
            # (a failed write's rollback frees pages for a moment), so a job may still slip in
            # between: it is accepted, and then it must lose nothing either.
            accepted, refused = [], None
            for _ in range(20):
                r = httpx.post(server.url + "/v1/sweeps", json=sweep_of(3, "gripper", ["end_effector.x"]), timeout=60)
                if r.status_code == 503:
                    refused = r
                    break
                assert r.status_code == 202, r.text
                accepted.append(r.json()["id"])
                time.sleep(0.5)
            assert refused is not None, "no request was refused while the disk was full"
            assert refused.json()["error"]["code"] == "store_unavailable" and refused.headers["Retry-After"] == "5"
            subprocess.run(["mount", "-o", "remount,size=256m", str(disk)], check=True)
            final = client.wait(job.id, timeout=300)
            for other in accepted:
                extra = client.wait(other, timeout=300)
                assert extra.status == "succeeded" and extra.progress.done == 3
        assert final.status == "succeeded" and final.progress.done == 3000, final.error
        assert stored_indices(disk / "data" / "flexmech.db", job.id) == list(range(3000))
        log = server.output(tail=None)
        assert "job store unavailable" in log and "Traceback" not in log
        assert log.count("job store unavailable, retrying") == 1  # once, not once per attempt
    finally:
        server.stop()
        subprocess.run(["umount", "-l", str(disk)], capture_output=True)


def _store_failing_on_purpose(tmp_path: Path) -> None:
    """The same promise, in-process: a store whose writes fail for 3 s mid-job."""
    from sqlalchemy.exc import OperationalError

    from flexmech.service.jobs.executors import ProcessPool
    from flexmech.service.jobs.kinds import kind_named
    from flexmech.service.jobs.runner import JobRunner
    from flexmech.service.jobs.store import JobStore
    from flexmech.service.requests import Limits

    class FullDisk(JobStore):
        failing_until = 0.0

        def add_points(self, *args, **kwargs):
            if time.monotonic() < self.failing_until:
                raise OperationalError("INSERT", {}, Exception("database or disk is full"))
            return super().add_points(*args, **kwargs)

    store = FullDisk(f"sqlite:///{tmp_path / 'jobs.db'}")
    spec = {
        "document": json.loads((EXAMPLES / "gripper.json").read_text()),
        "parameters": [{"path": ACTUATION, "values": [k * 0.1 for k in range(400)]}],
        "outputs": ["end_effector.x"],
    }
    plan = kind_named("sweep").prepare(spec, Limits())
    job = store.create("sweep", "", spec, plan.meta, plan.total)
    runner = JobRunner(store, ProcessPool(2), chunk_size=4)
    store.failing_until = time.monotonic() + 3.0
    runner.start()
    try:
        wait_for(lambda: store.get(job.id).status == "succeeded", 120, "the job did not finish")
    finally:
        runner.stop()
        runner.executor.close()
    assert store.get(job.id).done == 400 and sorted(store.points(job.id)) == list(range(400))
