"""Latency and throughput of POST /v1/solve over loopback, against a real uvicorn server, beside
a FastAPI app with nothing in it on the same uvicorn with the same clients (issue 47: at least
0.7 of its requests per second with 4 clients, and a p50 at most twice its own).

The gripper of seed 000, its document sent inline in every request (as a design tool would), two
ways: the same request again and again (the issue's measure; answers of a repeated request are
kept by api.answer_cache, so this is the repeat's path), and every request a different load
(each one validated, sent to a solver worker, solved and encoded: the whole small-solve path).
Side by side in the same run: what a request that does no work (a 404) costs through the same
clients and server, the bare app's 404 (the framework's and the clients' floor), and the same
solve through the Python API in-process (no HTTP). Small solves beside the largest analyses the
limits allow: benchmarks.beside_large.

    python3 -m benchmarks.api_latency [--requests 400] [--clients 4] [--url URL]

Without --url it starts `flexmech serve` on a free port (SQLite store in a temporary folder) and
stops it afterwards.
"""

from __future__ import annotations

import argparse
import itertools
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

from flexmech.models import compile_mechanism, load_document
from flexmech.service import solve_equilibrium

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "gripper.json"
ACTUATION = "/loads/actuation/force/1"
TARGET_RPS_RATIO = 0.7  # issue 47: of the bare app's requests per second, 4 clients
TARGET_P50_RATIO = 2.0  # issue 47: the p50 at most twice the bare app's


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
        [sys.executable, "-m", "flexmech.api.cli", "serve", "--host", "127.0.0.1", "--port", str(port)],
        cwd=REPO,
        env=env,
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


def latency(url: str, body, n: int) -> list[float]:
    """Seconds of n sequential solves, body() the next request's body."""
    times = []
    with httpx.Client(base_url=url, timeout=30) as client:
        for _ in range(20):  # warm: graphs built, connection open
            client.post("/v1/solve", json=body()).raise_for_status()
        for _ in range(n):
            sent = body()
            t = time.perf_counter()
            r = client.post("/v1/solve", json=sent)
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


def throughput(url: str, body, clients: int, per_client: int) -> tuple[float, int]:
    errors = []

    def send(client):
        if client.post("/v1/solve", json=body()).status_code != 200:
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


def in_process(document: dict, n: int) -> tuple[float, float]:
    """(p50 s of parse + compile + solve, p50 s of a solve of a compiled mechanism): the Python
    API in this process, with the document compiled per call as the server does, and once."""
    mech = compile_mechanism(load_document(document)).with_values({ACTUATION: 50.0})
    per_call, compiled_once = [], []
    for k in range(n + 20):
        t = time.perf_counter()
        solve_equilibrium(compile_mechanism(load_document(document)).with_values({ACTUATION: 50.0}))
        dt = time.perf_counter() - t
        t = time.perf_counter()
        solve_equilibrium(mech)
        if k >= 20:
            per_call.append(dt)
            compiled_once.append(time.perf_counter() - t)
    return statistics.median(per_call), statistics.median(compiled_once)


def verdict(ok: bool) -> str:
    return "met" if ok else "NOT met"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--requests", type=int, default=400)
    parser.add_argument("--clients", type=int, default=4)
    parser.add_argument("--url", default=None, help="a running server (default: start one)")
    args = parser.parse_args()

    document = json.loads(EXAMPLE.read_text())
    loads = itertools.count()

    def same() -> dict:
        return {"document": document, "overrides": {ACTUATION: 50.0}}

    def distinct() -> dict:  # a load no request had before: solved every time
        return {"document": document, "overrides": {ACTUATION: 50.0 + 1e-6 * next(loads)}}

    per_client = args.requests // args.clients * 2
    figures = {}
    with served(args.url) as url:
        for name, body in (("the same request", same), ("a different load each", distinct)):
            figures[name] = (latency(url, body, args.requests), *throughput(url, body, args.clients, per_client))
        empty_p50, empty_rps = floor(url, args.clients, args.requests)
    bare_p50, bare_rps = framework_floor(args.clients, args.requests)
    per_call, compiled_once = in_process(document, args.requests)

    ms = 1e3
    print(f"POST /v1/solve, gripper, document inline, {args.requests} sequential requests and {args.clients} clients")
    print(
        f"  the bare FastAPI app's 404 (no middleware, same uvicorn and clients): p50 {bare_p50 * ms:.2f} ms, "
        f"{bare_rps:.0f} requests/s"
    )
    print(f"  the service's own 404 (same clients and server): p50 {empty_p50 * ms:.2f} ms, {empty_rps:.0f} requests/s")
    for name, (times, rps, failed) in figures.items():
        p50 = statistics.median(times)
        rps_ratio, p50_ratio = rps / bare_rps, p50 / bare_p50
        print(
            f"  {name}: p50 {p50 * ms:.2f} ms  p99 {percentile(times, 99) * ms:.2f} ms, {rps:.0f} requests/s "
            f"({failed} failed): {rps_ratio:.2f} of the bare app's requests/s (target >= {TARGET_RPS_RATIO:g}: "
            f"{verdict(rps_ratio >= TARGET_RPS_RATIO)}), p50 {p50_ratio:.2f} x its p50 (target <= "
            f"{TARGET_P50_RATIO:g}: {verdict(p50_ratio <= TARGET_P50_RATIO)})"
        )
    print("in-process Python API, same run:")
    print(
        f"  parse + compile + solve: p50 {per_call * ms:.2f} ms; solve of a compiled mechanism: {compiled_once * ms:.2f} ms"
    )


if __name__ == "__main__":
    main()
