"""The job store's quotas, deletion, retention and documents kept once, on SQLite and
PostgreSQL, through service.jobs.store (no server: the HTTP side is test_store_limits_http)."""

from __future__ import annotations

import sqlite3
import threading
import uuid
from datetime import timedelta
from pathlib import Path

import pytest
from sqlalchemy import create_engine, text

from flexmech.service.jobs.quotas import QuotaExceeded, Quotas
from flexmech.service.jobs.retention import RetentionPurge
from flexmech.service.jobs.store import JobStore, utcnow
from flexmech.service.jobs.store_accounting import PACK_BYTES

DOCUMENT = {"name": "plate", "description": "d" * 15_000, "bodies": {"ground": {"fixed": True}}}


def never_failed(_point: dict) -> bool:
    return False


@pytest.fixture(params=["sqlite", "postgresql"])
def store_url(request, tmp_path) -> str:
    if request.param == "sqlite":
        return f"sqlite:///{tmp_path / 'jobs.db'}"
    from servers import fresh_database

    server = request.getfixturevalue("postgres_server_url")
    return fresh_database(server, f"quota_{uuid.uuid4().hex[:12]}")


def test_a_keys_sixth_job_is_refused_while_another_key_stores_and_a_delete_frees_a_place(store_url):
    store = JobStore(store_url, Quotas(max_jobs=5, max_bytes=10**9, max_running=100))
    mine = [store.create("sweep", "a", {"n": k}, {}, 2, document=DOCUMENT) for k in range(5)]
    with pytest.raises(QuotaExceeded) as refused:
        store.create("sweep", "a", {"n": 5}, {}, 2, document=DOCUMENT)
    assert (refused.value.quota, refused.value.used, refused.value.limit) == ("jobs", 5, 5)
    assert "5 used of 5" in str(refused.value) and "DELETE /v1/jobs/{id}" in str(refused.value)
    store.create("sweep", "b", {}, {}, 2, document=DOCUMENT)  # another key's quota is its own
    assert store.delete(mine[0].id) > 0
    assert store.get(mine[0].id) is None
    store.create("sweep", "a", {"n": 6}, {}, 2, document=DOCUMENT)
    assert store.usage("a").jobs == 5 and store.usage("b").jobs == 1
    store.close()


def test_one_key_racing_for_its_last_place_gets_it_once(store_url):
    """Eight threads of one key create at once with room for three: the owner's row is locked
    for each creation, so exactly three land."""
    store = JobStore(store_url, Quotas(max_jobs=3, max_bytes=10**9, max_running=100))
    outcomes: list[str] = []

    def create(k: int) -> None:
        try:
            store.create("sweep", "a", {"n": k}, {}, 1, document=DOCUMENT)
            outcomes.append("stored")
        except QuotaExceeded:
            outcomes.append("refused")
        except Exception as exc:  # SQLite's lock wait may run out under 8 writers: a 503 to the caller
            outcomes.append(type(exc).__name__)

    threads = [threading.Thread(target=create, args=(k,)) for k in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert outcomes.count("stored") == 3 == store.usage("a").jobs, outcomes
    store.close()


def test_running_and_byte_quotas_count_what_the_store_holds(store_url):
    store = JobStore(store_url, Quotas(max_jobs=100, max_bytes=60_000, max_running=2))
    first = store.create("sweep", "a", {"n": 1}, {}, 1, document=DOCUMENT)
    store.create("sweep", "a", {"n": 2}, {}, 1, document=DOCUMENT)
    with pytest.raises(QuotaExceeded) as running:
        store.create("sweep", "a", {"n": 3}, {}, 1, document=DOCUMENT)
    assert running.value.quota == "running"
    store.finish(first.id, "succeeded")
    used = store.usage("a")
    assert used.running == 1 and DOCUMENT["description"] and 15_000 < used.bytes < 16_000  # the document once
    other = dict(DOCUMENT, description="e" * 45_000)  # a new document: its bytes count
    with pytest.raises(QuotaExceeded) as full:
        store.create("sweep", "a", {}, {}, 1, document=other)
    assert full.value.quota == "bytes" and full.value.needed > 45_000
    store.close()


def test_forty_jobs_of_one_document_store_it_once_and_the_last_delete_removes_it(store_url):
    store = JobStore(store_url)
    jobs = [store.create("sweep", "a" if k % 2 else "b", {"n": k}, {}, 1, document=DOCUMENT) for k in range(40)]
    totals = store.totals()
    assert totals["documents"] == 1
    document_bytes = len(DOCUMENT["description"]) + 60
    assert totals["bytes"] < document_bytes + 40 * 200, totals  # one copy, and forty small specs
    assert store.get(jobs[7].id).spec == {"document": DOCUMENT, "n": 7}  # read back whole, keys in order
    assert list(store.get(jobs[7].id).spec["document"]) == list(DOCUMENT)
    for job in jobs[:-1]:
        store.delete(job.id)
    assert store.totals()["documents"] == 1
    store.delete(jobs[-1].id)
    assert store.totals() | {"database_bytes": None} == {
        "jobs": 0,
        "running": 0,
        "documents": 0,
        "bytes": 0,
        "database_bytes": None,
    }
    store.close()


def test_a_large_point_is_stored_compressed_and_read_back_whole(store_url):
    store = JobStore(store_url)
    job = store.create("export", "a", {}, {}, 2, document=DOCUMENT)
    archive = "QUJD" * (PACK_BYTES // 2)  # base64 text past the packing size
    store.add_points(job.id, [(0, {"archive": archive}), (1, {"status": "converged"})], never_failed)
    assert store.points(job.id) == {0: {"archive": archive}, 1: {"status": "converged"}}
    assert store.usage("a").bytes < len(DOCUMENT["description"]) + len(archive) / 10  # compressed
    store.close()


def test_points_of_a_deleted_job_are_dropped_not_retried(store_url):
    store = JobStore(store_url)
    job = store.create("sweep", "a", {}, {}, 2, document=DOCUMENT)
    store.delete(job.id)
    assert store.add_points(job.id, [(0, {"status": "converged"})], never_failed) == 0
    assert store.statuses([job.id]) == {}
    store.close()


def test_retention_purges_ended_jobs_in_batches_and_keeps_active_ones(store_url):
    store = JobStore(store_url)
    ended = [store.create("sweep", "a", {}, {}, 1, document=dict(DOCUMENT, name=f"p{k}")) for k in range(5)]
    running = store.create("sweep", "b", {}, {}, 1, document=DOCUMENT)
    for job in ended:
        store.finish(job.id, "succeeded")
    assert RetentionPurge(store, timedelta(hours=1)).purge_once() == 0  # not yet expired
    assert store.purge_ended_before(utcnow() + timedelta(seconds=1), batch=2) == 2
    assert RetentionPurge(store, timedelta(microseconds=1)).purge_once() == 3
    assert store.get(running.id) is not None and store.totals()["documents"] == 1
    store.close()


def test_an_sqlite_file_stops_growing_when_jobs_are_deleted(tmp_path):
    """Jobs of 100 kB stored and deleted, twenty times: the file's freed pages go back (a new
    file has incremental auto-vacuum), so it ends about as large as after the first."""
    store = JobStore(f"sqlite:///{tmp_path / 'jobs.db'}")
    sizes = []
    for k in range(20):
        job = store.create("sweep", "a", {}, {}, 50, document=dict(DOCUMENT, name=f"p{k}"))
        store.add_points(job.id, [(i, {"v": [float(i + k)] * 200}) for i in range(50)], never_failed)
        store.delete(job.id)
        sizes.append(store.database_bytes())
    store.compact()
    database = Path(tmp_path / "jobs.db").stat().st_size
    assert database < 300_000, (database, sizes)
    store.close()


def test_a_store_opened_while_another_process_holds_the_write_lock_still_reads(tmp_path):
    """A new connection of the pool, opened while a writer holds SQLite's lock, reads the jobs:
    its settings must not need the lock (setting auto_vacuum did, and failed as 'locked')."""
    path = tmp_path / "jobs.db"
    JobStore(f"sqlite:///{path}").create("sweep", "a", {}, {}, 2, document=DOCUMENT)
    lock = sqlite3.connect(path, isolation_level=None)
    lock.execute("BEGIN EXCLUSIVE")
    try:
        reader = JobStore(f"sqlite:///{path}")  # its first connection opens under the lock
        assert reader.usage("a").jobs == 1
        assert sqlite3.connect(path).execute("PRAGMA auto_vacuum").fetchone()[0] == 2  # incremental
        reader.close()
    finally:
        lock.execute("COMMIT")
        lock.close()


OLD_SCHEMA = [
    "CREATE TABLE flexmech_jobs (id VARCHAR(32) PRIMARY KEY, kind VARCHAR(32), owner VARCHAR(64), "
    "status VARCHAR(16), spec JSON, plan JSON, total INTEGER, done INTEGER, failed_points INTEGER, "
    "error TEXT, created_at DATETIME, started_at DATETIME, finished_at DATETIME, restarts INTEGER)",
    "CREATE TABLE flexmech_job_points (job_id VARCHAR(32) REFERENCES flexmech_jobs(id) ON DELETE CASCADE, "
    '"index" INTEGER, data JSON, finished_at DATETIME, PRIMARY KEY (job_id, "index"))',
]


def test_a_store_made_before_quotas_keeps_its_jobs_and_counts_their_bytes(tmp_path):
    url = f"sqlite:///{tmp_path / 'old.db'}"
    engine = create_engine(url)
    spec = '{"document": {"name": "' + "n" * 1000 + '", "bodies": {}}, "steps": 3}'
    with engine.begin() as connection:
        for statement in OLD_SCHEMA:
            connection.execute(text(statement))
        connection.execute(
            text(
                "INSERT INTO flexmech_jobs VALUES ('00000000000000000000000000000001', 'sweep', 'a', 'succeeded', "
                ":spec, '{}', 1, 1, 0, NULL, '2026-01-01 00:00:00', NULL, '2026-01-01 00:00:01', 0)"
            ),
            {"spec": spec},
        )
        connection.execute(
            text(
                "INSERT INTO flexmech_job_points VALUES ('00000000000000000000000000000001', 0, "
                "'{\"status\": \"converged\"}', '2026-01-01 00:00:01')"
            )
        )
    engine.dispose()
    store = JobStore(url)
    job = store.get("00000000000000000000000000000001")
    assert job.spec["steps"] == 3 and len(job.spec["document"]["name"]) == 1000
    assert store.points(job.id) == {0: {"status": "converged"}}
    assert store.usage("a").bytes >= len(spec)
    [(listed, name)] = store.recent("a", 5)
    assert listed.id == job.id and name == "n" * 200 + "..."  # listings abridge a long name
    assert store.purge_ended_before(utcnow()) == 1 and store.usage("a").bytes == 0
    store.close()
