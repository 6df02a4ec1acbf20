"""Latency and throughput of POST /v1/solve over loopback, against a real uvicorn server.

The gripper of seed 000 at F = 50 uN, its document sent inline in every request (as a design
tool would). Side by side in the same run: the same solve through the Python API in-process
(no HTTP), so the ratio shows what the service adds. Prints p50/p99 over the requests, and
requests per second with 4 concurrent clients (each its own keep-alive connection).

    python3 -m benchmarks.api_latency [--requests 200] [--clients 4] [--url URL]

Without --url it starts `uvicorn --factory api.app:create_app` on a free port (SQLite store in
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
from pathlib import Path

import httpx
import numpy as np

from models import compile_mechanism, load_document
from service import solve_equilibrium

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "gripper.json"
ACTUATION = "/loads/actuation/force/1"
TARGET_P50_MS = 10.0


def start_server(data_dir: str) -> tuple[subprocess.Popen, str]:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = {**os.environ, "FLEXMECH_DATA_DIR": data_dir, "FLEXMECH_WORKERS": "1", "FLEXMECH_API_KEYS": ""}
    proc = subprocess.Popen([sys.executable, "-m", "uvicorn", "--factory", "api.app:create_app", "--host",
                             "127.0.0.1", "--port", str(port), "--log-level", "warning"], cwd=REPO, env=env)
    url = f"http://127.0.0.1:{port}"
    for _ in range(600):
        try:
            if httpx.get(url + "/v1/health", timeout=1).status_code == 200:
                return proc, url
        except httpx.HTTPError:
            time.sleep(0.1)
    proc.kill()
    raise SystemExit("the server did not start")


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


def throughput(url: str, body: dict, clients: int, per_client: int) -> tuple[float, int]:
    errors = []
    barrier = threading.Barrier(clients + 1)

    def work():
        with httpx.Client(base_url=url, timeout=30) as client:
            client.post("/v1/solve", json=body)
            barrier.wait()
            for _ in range(per_client):
                if client.post("/v1/solve", json=body).status_code != 200:
                    errors.append(1)

    threads = [threading.Thread(target=work) for _ in range(clients)]
    for t in threads:
        t.start()
    barrier.wait()
    started = time.perf_counter()
    for t in threads:
        t.join()
    return clients * per_client / (time.perf_counter() - started), len(errors)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--requests", type=int, default=200)
    parser.add_argument("--clients", type=int, default=4)
    parser.add_argument("--url", default=None, help="a running server (default: start one)")
    args = parser.parse_args()

    document = json.loads(EXAMPLE.read_text())
    body = {"document": document, "overrides": {ACTUATION: 50.0}}

    proc = None
    with tempfile.TemporaryDirectory() as data_dir:
        url = args.url
        if url is None:
            proc, url = start_server(data_dir)
        try:
            http = latency(url, body, args.requests)
            rps, failed = throughput(url, body, args.clients, args.requests // args.clients * 2)
        finally:
            if proc is not None:
                proc.terminate()
                proc.wait(10)

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
    print(f"  p50 {p50:.2f} ms   p99 {percentile(http, 99) * ms:.2f} ms   (target p50 <= {TARGET_P50_MS:g} ms: "
          f"{'met' if p50 <= TARGET_P50_MS else 'NOT met'})")
    print(f"  {args.clients} concurrent clients: {rps:.0f} requests/s ({failed} failed)")
    print("in-process Python API, same run:")
    print(f"  parse + compile + solve: p50 {statistics.median(per_call) * ms:.2f} ms; "
          f"solve of a compiled mechanism: p50 {statistics.median(compiled_once) * ms:.2f} ms")
    print(f"  HTTP p50 / in-process (parse + compile + solve) p50 = {p50 / (statistics.median(per_call) * ms):.2f}")


if __name__ == "__main__":
    main()
