"""Quotas, deletion, retention and documents kept once, through a real server (uvicorn, the
API, the runner): the attacks of issue 52 with one valid key."""

from __future__ import annotations

import sqlite3
import time
from pathlib import Path

import pytest
from conftest import ACTUATION, make_deployment

from flexmech.api.client import Client, FlexmechError

KEYS = ("quota-first-key-0123", "quota-second-key-0123")


def small_sweep(document: dict | None = None, steps: int = 2, **extra) -> dict:
    source = {"document": document} if document is not None else {"example": "gripper"}
    return {"parameters": [{"path": ACTUATION, "start": 0.0, "stop": 40.0, "steps": steps}], **source, **extra}


@pytest.fixture(scope="module")
def gripper(tmp_path_factory) -> dict:
    import json

    from conftest import EXAMPLES

    return json.loads((EXAMPLES / "gripper.json").read_text())


@pytest.mark.parametrize("backend", ["sqlite", "postgresql"])
def test_a_keys_sixth_sweep_is_429_while_another_keys_is_accepted_until_it_deletes_one(backend, request, tmp_path):
    server = make_deployment(backend, request, tmp_path).start(
        FLEXMECH_API_KEYS=",".join(KEYS), FLEXMECH_KEY_MAX_JOBS="5"
    )
    try:
        with Client(server.url, api_key=KEYS[0]) as first, Client(server.url, api_key=KEYS[1]) as second:
            jobs = [first.sweep(**small_sweep()) for _ in range(5)]
            with pytest.raises(FlexmechError) as refused:
                first.sweep(**small_sweep())
            assert refused.value.status == 429 and refused.value.code == "quota_exceeded"
            assert refused.value.details["quota"] == "jobs"
            assert (refused.value.details["used"], refused.value.details["limit"]) == (5, 5)
            assert "DELETE /v1/jobs/{id}" in refused.value.details["free"]
            assert "stored jobs reached: 5 used of 5" in refused.value.message
            assert second.sweep(**small_sweep()).status == "queued"
            assert first.usage().jobs.used == 5 and second.usage().jobs.used == 1
            first.wait(jobs[0].id, timeout=120)
            deleted = first.delete(jobs[0].id)
            assert deleted.deleted and deleted.freed_bytes > 0 and deleted.usage.jobs.used == 4
            with pytest.raises(FlexmechError) as gone:
                first.job(jobs[0].id)
            assert gone.value.status == 404
            assert first.wait(first.sweep(**small_sweep()).id, timeout=120).status == "succeeded"
    finally:
        server.stop()


def test_forty_sweeps_of_one_document_store_it_once(request, tmp_path, gripper):
    document = dict(gripper, description="a gripper of a long description. " * 500)  # 16.5 kB
    deployment = make_deployment("sqlite", request, tmp_path)
    server = deployment.start(FLEXMECH_KEY_MAX_RUNNING="64")
    try:
        with Client(server.url) as client:
            jobs = [client.sweep(**small_sweep(document, outputs=["end_effector.x"])) for _ in range(40)]
            for job in jobs:
                client.wait(job.id, timeout=300)
            store = client.health().store
            assert client.job_request(jobs[-1].id)["document"] == document
    finally:
        server.stop()
    database = Path(deployment.env["FLEXMECH_DATA_DIR"]) / "flexmech.db"
    with sqlite3.connect(database) as connection:
        connection.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    copies = 40 * len(document["description"])  # 660 kB, were each job to keep its own
    print(f"\nstored {store.bytes} B, database file {database.stat().st_size} B; forty copies {copies} B")
    assert store.documents == 1 and store.jobs == 40
    assert store.bytes < copies / 4, store  # one copy, forty specs, plans and 3-point results
    assert database.stat().st_size < copies / 2


def test_a_running_job_can_be_deleted_and_ended_jobs_are_purged_after_the_retention(request, tmp_path):
    server = make_deployment("sqlite", request, tmp_path).start(FLEXMECH_JOB_RETENTION="3")
    try:
        with Client(server.url) as client:
            long = client.sweep(**small_sweep(steps=19_999), continuation=ACTUATION, outputs=["end_effector.x"])
            short = client.sweep(**small_sweep())
            assert client.wait(short.id, timeout=120).status == "succeeded"
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline and _exists(client, short.id):
                time.sleep(0.2)
            assert not _exists(client, short.id)  # purged some 3 s after it ended
            assert client.job(long.id).status == "running"  # an active job is never purged
            deleted = client.delete(long.id)
            assert deleted.status == "running" and deleted.usage.jobs.used == 0
            assert not _exists(client, long.id)
            assert client.wait(client.sweep(**small_sweep()).id, timeout=120).status == "succeeded"  # runner fine
            store = client.health().store
    finally:
        server.stop()
    assert store.retention_seconds == 3 and store.jobs <= 1 and store.documents == store.jobs  # the last sweep


def _exists(client: Client, job_id: str) -> bool:
    try:
        client.job(job_id)
    except FlexmechError as missing:
        assert missing.status == 404
        return False
    return True


LOOP_SECONDS = 30  # 60 s in issue 52's words: the same test at 60 s held 1,003,918 B (x1.47 on disk)
QUOTA = 1_000_000
RUNNING = 4


def test_a_key_posting_sweeps_for_a_while_stays_within_its_byte_quota(request, tmp_path, gripper):
    """Key A posts sweeps of ever new documents (15 kB each) with 400-point results for LOOP_SECONDS;
    key B's job, stored before, is untouched. A's bytes pass its quota by at most a task's
    points of each of its running jobs, and the database file holds the two keys' bytes plus
    SQLite's overhead (docs/service.md states it)."""
    deployment = make_deployment("sqlite", request, tmp_path)
    server = deployment.start(
        FLEXMECH_API_KEYS=",".join(KEYS), FLEXMECH_KEY_MAX_BYTES=str(QUOTA), FLEXMECH_KEY_MAX_RUNNING=str(RUNNING)
    )
    answers: dict[int, int] = {}
    try:
        with Client(server.url, api_key=KEYS[0]) as first, Client(server.url, api_key=KEYS[1]) as second:
            kept = second.wait(second.sweep(**small_sweep(gripper, steps=50)).id, timeout=120)
            kept_points = second.result(kept.id).result.points
            started, k = time.monotonic(), 0
            while time.monotonic() - started < LOOP_SECONDS:
                k += 1
                document = dict(gripper, description=f"variant {k} " + "x" * 15_000)
                try:
                    first.sweep(**small_sweep(document, steps=399, outputs=["end_effector.x", "end_effector.y"]))
                    answers[202] = answers.get(202, 0) + 1
                except FlexmechError as refused:
                    answers[refused.status] = answers.get(refused.status, 0) + 1
                    time.sleep(0.05)
            for job in first.recent_jobs(limit=100).jobs:
                if not job.finished:
                    first.wait(job.id, timeout=120)
            used = first.usage().bytes.used
            other = second.usage().bytes.used
            assert second.job(kept.id).status == "succeeded"
            assert second.result(kept.id).result.points == kept_points
            failed = [j.error for j in first.recent_jobs(limit=100).jobs if j.status == "failed"]
    finally:
        server.stop()
    database = Path(deployment.env["FLEXMECH_DATA_DIR"]) / "flexmech.db"
    with sqlite3.connect(database) as connection:
        connection.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    size = database.stat().st_size
    print(f"\n{answers}; key A {used} B, key B {other} B, database file {size} B; failed: {failed[:1]}")
    assert answers.get(202, 0) >= 3 and answers.get(429, 0) > 10 and set(answers) <= {202, 429}
    assert QUOTA * 0.9 < used <= QUOTA + RUNNING * 20_000  # past it by a task's points per running job at most
    assert all("quota of stored bytes" in error for error in failed)
    assert size <= 1.5 * (QUOTA + RUNNING * 20_000 + other) + 200_000
