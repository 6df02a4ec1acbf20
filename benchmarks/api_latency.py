"""Latency and throughput of POST /v1/solve over loopback, against a real uvicorn server.

The gripper of seed 000 at F = 50 uN, its document sent inline in every request (as a design
tool would). Side by side in the same run: the same solve through the Python API in-process
(no HTTP), so the ratio shows what the service adds. Prints p50/p99 over the requests, and
requests per second with 4 concurrent clients (each its own keep-alive connection), and the
same 4 clients' latency while one long simulation (the rod of Lan's Example I.1 at a 0.1 ms
step, which runs into the server's 10 s solve limit) holds the server's solver: the long run's
wall time against its limit is printed too, and what a request that does no work (a 404)
costs through the same clients and server: the floor under every figure above; and the same
404 from a FastAPI app with nothing in it, on the same uvicorn: the framework's own floor.

    python3 -m benchmarks.api_latency [--requests 200] [--clients 4] [--url URL]

Without --url it starts `flexmech serve` on a free port (SQLite store in
a temporary folder) and stops it afterwards.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from contextlib import contextmanager
from pathlib import Path

import httpx
import numpy as np

from models import compile_mechanism, load_document
from service import solve_equilibrium

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "gripper.json"
ACTUATION = "/loads/actuation/force/1"
TARGET_P50_MS = 2.0  # issue 24
TARGET_RPS = 1000.0  # issue 24, with 4 clients


def start_server(data_dir: str, settings: dict[str, str] | None = None) -> tuple[subprocess.Popen, str]:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = {
        **os.environ,
        "FLEXMECH_DATA_DIR": data_dir,
        "FLEXMECH_WORKERS": "1",
        "FLEXMECH_API_KEYS": "",
        "FLEXMECH_LOG_LEVEL": "warning",
        **(settings or {}),
    }
    proc = subprocess.Popen(
        [sys.executable, "-m", "service.cli", "serve", "--host", "127.0.0.1", "--port", str(port)], cwd=REPO, env=env
    )
    url = f"http://127.0.0.1:{port}"
    for _ in range(600):
        try:
            if httpx.get(url + "/v1/health", timeout=1).status_code == 200:
                return proc, url
        except httpx.HTTPError:
            time.sleep(0.1)
    proc.kill()
    raise SystemExit("the server did not start")


@contextmanager
def served(url: str | None, settings: dict[str, str] | None = None, empty_cache: bool = False):
    """The server at url, or one started here (SQLite in a temporary folder, FLEXMECH_*
    `settings` over the defaults; empty_cache: its graph and kernel cache in that folder too)
    and stopped after."""
    if url is not None:
        yield url
        return
    with tempfile.TemporaryDirectory() as data_dir:
        if empty_cache:
            settings = {**(settings or {}), "FLEXMECH_CACHE_DIR": os.path.join(data_dir, "cache")}
        proc, url = start_server(data_dir, settings)
        try:
            yield url
        finally:
            proc.terminate()
            proc.wait(10)


def percentile(values: list[float], q: float) -> float:
    return float(np.percentile(values, q))


def latency(url: str, body: dict, n: int) -> list[float]:
    times = []
    with httpx.Client(base_url=url, timeout=30) as client:
        for _ in range(20):  # warm: graphs built, connection open
            client.post("/v1/solve", json=body).raise_for_status()
        for _ in range(n):
            t = time.perf_counter()
            r = client.post("/v1/solve", json=body)
            times.append(time.perf_counter() - t)
            if r.status_code != 200 or r.json()["status"] != "converged":
                raise SystemExit(f"unexpected answer: {r.status_code} {r.text[:300]}")
    return times


def concurrently(url: str, clients: int, requests: int, send) -> float:
    """Requests per second of `clients` threads, each with its own keep-alive connection,
    each calling send(client) `requests` times once all are connected."""
    barrier = threading.Barrier(clients + 1)

    def work():
        with httpx.Client(base_url=url, timeout=30) as client:
            send(client)  # connected and warm
            barrier.wait()
            for _ in range(requests):
                send(client)

    threads = [threading.Thread(target=work) for _ in range(clients)]
    for t in threads:
        t.start()
    barrier.wait()
    started = time.perf_counter()
    for t in threads:
        t.join()
    return clients * requests / (time.perf_counter() - started)


def throughput(url: str, body: dict, clients: int, per_client: int) -> tuple[float, int]:
    errors = []

    def send(client):
        if client.post("/v1/solve", json=body).status_code != 200:
            errors.append(1)

    return concurrently(url, clients, per_client, send), len(errors)


def floor(url: str, clients: int, n: int, path: str = "/v1/no-such-path") -> tuple[float, float]:
    """(p50 s, requests/s with `clients`) of a request that does no work (GET of a path that
    does not exist: 404) through the same clients and server: what HTTP alone costs here."""

    def send(client):
        if client.get(path).status_code != 404:
            raise SystemExit("the empty request did not answer 404")

    with httpx.Client(base_url=url, timeout=30) as client:
        times = []
        for _ in range(n):
            t = time.perf_counter()
            send(client)
            times.append(time.perf_counter() - t)
    return statistics.median(times), concurrently(url, clients, n, send)


BARE_APP = """from fastapi import FastAPI

app = FastAPI()


@app.get("/ping")
async def ping():
    return {"ok": True}
"""


def framework_floor(clients: int, n: int) -> tuple[float, float]:
    """floor() of a FastAPI app with no middleware and nothing else (its 404), on the same
    uvicorn (httptools, uvloop) with the same clients: what the framework and the clients
    alone cost on this machine."""
    import socket

    with tempfile.TemporaryDirectory() as folder, socket.socket() as s:
        Path(folder, "bare_app.py").write_text(BARE_APP)
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        s.close()
        proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "uvicorn",
                "bare_app:app",
                "--port",
                str(port),
                "--log-level",
                "warning",
                "--http",
                "httptools",
                "--loop",
                "uvloop",
            ],
            cwd=folder,
        )
        url = f"http://127.0.0.1:{port}"
        try:
            for _ in range(300):
                try:
                    httpx.get(url + "/ping", timeout=1)
                    break
                except httpx.HTTPError:
                    time.sleep(0.1)
            return floor(url, clients, n, path="/no-such-path")
        finally:
            proc.terminate()
            proc.wait(10)


def during_long_run(url: str, body: dict, clients: int) -> tuple[list[float], float, str]:
    """(latencies of the clients' solves while the long run lasted, its wall seconds, its status)."""
    rod = {"example": "rod_free_vibration", "analysis": "simulate", "simulate": {"until": 2, "step": 1e-4}}
    outcome = {}

    def long_run():
        t = time.perf_counter()
        r = httpx.post(url + "/v1/solve", json=rod, timeout=120)
        outcome["seconds"] = time.perf_counter() - t
        outcome["status"] = r.json().get("status") if r.status_code == 200 else f"HTTP {r.status_code}"

    times: list[float] = []

    def client_loop():
        with httpx.Client(base_url=url, timeout=30) as client:
            while "seconds" not in outcome:
                t = time.perf_counter()
                client.post("/v1/solve", json=body).raise_for_status()
                times.append(time.perf_counter() - t)

    runner = threading.Thread(target=long_run)
    runner.start()
    time.sleep(0.5)
    threads = [threading.Thread(target=client_loop) for _ in range(clients)]
    for t in threads:
        t.start()
    runner.join()
    for t in threads:
        t.join()
    return times, outcome["seconds"], outcome["status"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--requests", type=int, default=200)
    parser.add_argument("--clients", type=int, default=4)
    parser.add_argument("--url", default=None, help="a running server (default: start one)")
    args = parser.parse_args()

    document = json.loads(EXAMPLE.read_text())
    body = {"document": document, "overrides": {ACTUATION: 50.0}}

    with served(args.url) as url:
        http = latency(url, body, args.requests)
        rps, failed = throughput(url, body, args.clients, args.requests // args.clients * 2)
        busy, long_seconds, long_status = during_long_run(url, body, args.clients)
        empty_p50, empty_rps = floor(url, args.clients, args.requests)
    bare_p50, bare_rps = framework_floor(args.clients, args.requests)

    # the peer, in this process: the Python API with the document compiled per call, as the
    # server does, and with the document compiled once
    mech = compile_mechanism(load_document(document)).with_values({ACTUATION: 50.0})
    per_call, compiled_once = [], []
    for k in range(args.requests + 20):
        t = time.perf_counter()
        solve_equilibrium(compile_mechanism(load_document(document)).with_values({ACTUATION: 50.0}))
        dt = time.perf_counter() - t
        t = time.perf_counter()
        solve_equilibrium(mech)
        if k >= 20:
            per_call.append(dt)
            compiled_once.append(time.perf_counter() - t)

    ms = 1e3
    p50 = statistics.median(http) * ms
    print(f"POST /v1/solve, gripper at 50 uN, document inline, {args.requests} sequential requests over loopback")
    print(
        f"  p50 {p50:.2f} ms   p99 {percentile(http, 99) * ms:.2f} ms   (target p50 <= {TARGET_P50_MS:g} ms: "
        f"{'met' if p50 <= TARGET_P50_MS else 'NOT met'})"
    )
    print(f"  {args.clients} concurrent clients: {rps:.0f} requests/s ({failed} failed; target >= {TARGET_RPS:g})")
    print(
        f"  a request that does no work (404), same clients and server: p50 {empty_p50 * ms:.2f} ms, "
        f"{args.clients} clients {empty_rps:.0f} requests/s"
    )
    print(
        f"  the same 404 from a FastAPI app with nothing in it (no middleware, same uvicorn and clients): "
        f"p50 {bare_p50 * ms:.2f} ms, {args.clients} clients {bare_rps:.0f} requests/s"
    )
    print(
        f"  while a simulation ran into the 10 s solve limit ({long_seconds:.2f} s wall, status {long_status}): "
        f"{args.clients} clients' p50 {statistics.median(busy) * ms:.2f} ms  p99 {percentile(busy, 99) * ms:.2f} ms  "
        f"max {max(busy) * ms:.1f} ms over {len(busy)} solves (target p99 < 100 ms)"
    )
    print("in-process Python API, same run:")
    print(
        f"  parse + compile + solve: p50 {statistics.median(per_call) * ms:.2f} ms; "
        f"solve of a compiled mechanism: p50 {statistics.median(compiled_once) * ms:.2f} ms"
    )
    print(f"  HTTP p50 / in-process (parse + compile + solve) p50 = {p50 / (statistics.median(per_call) * ms):.2f}")


if __name__ == "__main__":
    main()
