"""Issue 52's attack on the job store, replayed against a live `flexmech serve` (SQLite, two
keys, the default settings but FLEXMECH_KEY_MAX_JOBS=5 for the last part): for each, the
status it got and the seconds to the answer, and how much the database grew.

    python3 -m benchmarks.store_abuse

1. 40 sweeps of the gripper, each with a 990,000-character description (the issue: all
   accepted in 2.3 s, +58 MB); a 900 kB name.
2. 40 sweeps (one after another) of one document with a 19,000-character description: stored once.
3. Key A's sixth job over FLEXMECH_KEY_MAX_JOBS=5, key B's first, and A's after a DELETE.
"""

from __future__ import annotations

import json
import sqlite3
import tempfile
import time
from pathlib import Path

import httpx

from benchmarks.api_latency import start_server

REPO = Path(__file__).resolve().parents[1]
KEYS = ("store-abuse-key-aaaa", "store-abuse-key-bbbb")
GRIPPER = json.loads((REPO / "examples" / "gripper.json").read_text())
SWEEP = {"parameters": [{"path": "/loads/actuation/force/1", "start": 0.0, "stop": 40.0, "steps": 2}]}


def database_bytes(data_dir: str) -> int:
    database = Path(data_dir) / "flexmech.db"
    with sqlite3.connect(database) as connection:
        connection.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    return database.stat().st_size


def timed_post(client: httpx.Client, path: str, body: dict, key: str) -> tuple[int, float, dict]:
    started = time.perf_counter()
    answer = client.post(path, json=body, headers={"X-API-Key": key})
    return answer.status_code, time.perf_counter() - started, answer.json()


def attack(client: httpx.Client, data_dir: str) -> None:
    before = database_bytes(data_dir)
    long = dict(GRIPPER, description="x" * 990_000)
    answers = [timed_post(client, "/v1/sweeps", {**SWEEP, "document": long}, KEYS[0]) for _ in range(40)]
    statuses = sorted({status for status, _, _ in answers})
    slowest = max(seconds for _, seconds, _ in answers)
    print(f"40 sweeps, 990,000-character description: statuses {statuses}, slowest answer {slowest:.3f} s,")
    print(f"  pointer {answers[0][2]['error'].get('pointer')}; database grew {database_bytes(data_dir) - before} B")
    status, seconds, body = timed_post(
        client, "/v1/sweeps", {**SWEEP, "document": dict(GRIPPER, name="n" * 900_000)}, KEYS[0]
    )
    print(f"a 900 kB name: {status} in {seconds:.3f} s, pointer {body['error'].get('pointer')}")


def one_document(client: httpx.Client, data_dir: str) -> None:
    before = database_bytes(data_dir)
    document = dict(GRIPPER, description="y" * 19_000)
    for _ in range(40):  # one after another: FLEXMECH_KEY_MAX_RUNNING is 20
        body = {**SWEEP, "document": document, "outputs": ["end_effector.x"]}
        job_id = timed_post(client, "/v1/sweeps", body, KEYS[1])[2]["id"]
        wait(client, job_id, KEYS[1])
    grew = database_bytes(data_dir) - before
    store = client.get("/v1/health").json()["store"]
    print(
        f"40 sweeps of one 19,000-character document: {store['documents']} document(s) stored, "
        f"{store['bytes']} B counted, database file grew {grew} B (40 copies: {40 * 19_000} B)"
    )


def wait(client: httpx.Client, job_id: str, key: str) -> None:
    while client.get(f"/v1/jobs/{job_id}", headers={"X-API-Key": key}).json()["status"] in ("queued", "running"):
        time.sleep(0.05)


def quota(url: str) -> None:
    with httpx.Client(base_url=url, timeout=120) as client:
        body = {**SWEEP, "example": "gripper"}
        accepted = [timed_post(client, "/v1/sweeps", body, KEYS[0]) for _ in range(5)]
        status, seconds, refused = timed_post(client, "/v1/sweeps", body, KEYS[0])
        other, _, _ = timed_post(client, "/v1/sweeps", body, KEYS[1])
        print(f"FLEXMECH_KEY_MAX_JOBS=5: key A's 5 -> {[s for s, _, _ in accepted]}, sixth {status} in {seconds:.3f} s")
        print(f"  {refused['error']['message']}")
        print(f"  key B's first: {other}")
        first = accepted[0][2]["id"]
        wait(client, first, KEYS[0])
        deleted = client.delete(f"/v1/jobs/{first}", headers={"X-API-Key": KEYS[0]}).json()
        again, _, _ = timed_post(client, "/v1/sweeps", body, KEYS[0])
        print(f"  DELETE freed {deleted['freed_bytes']} B; key A's next: {again}")


def main() -> None:
    settings = {"FLEXMECH_API_KEYS": ",".join(KEYS), "FLEXMECH_EXAMPLES_DIR": str(REPO / "examples")}
    with tempfile.TemporaryDirectory() as data_dir:
        server, url = start_server(data_dir, settings)
        try:
            with httpx.Client(base_url=url, timeout=120) as client:
                attack(client, data_dir)
                one_document(client, data_dir)
        finally:
            server.terminate()
            server.wait(30)
    with tempfile.TemporaryDirectory() as data_dir:
        server, url = start_server(data_dir, {**settings, "FLEXMECH_KEY_MAX_JOBS": "5"})
        try:
            quota(url)
        finally:
            server.terminate()
            server.wait(30)


if __name__ == "__main__":
    main()
