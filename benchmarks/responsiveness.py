"""Does a small /v1/solve stay fast while the server simulates and compiles? A real uvicorn on
an empty kernel cache: a four-bar simulation job (1 s, the old "compiled": true included) makes
the build queue compile the four-bar's kernels while a worker runs the job interpreted; a
client sends the gripper's /v1/solve every 50 ms meanwhile. Printed: the small solve's p50 and
p99 while the build and the job run, when the job first showed progress and its windows, and
how long the builder took.

    python3 -m benchmarks.responsiveness
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time

import httpx

from benchmarks.api_latency import start_server


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["FLEXMECH_CACHE_DIR"] = os.path.join(tmp, "cache")
        proc, url = start_server(os.path.join(tmp, "data"))
        try:
            with httpx.Client(base_url=url, timeout=60) as client:
                assert client.post("/v1/solve", json={"example": "gripper"}).status_code == 200
                started = time.perf_counter()
                job = client.post(
                    "/v1/simulations",
                    json={"example": "four_bar_dynamics", "simulate": {"until": 1.0, "compiled": True}},
                ).json()
                times, first_progress, built, seen_busy = [], None, None, False
                while time.perf_counter() - started < 60:
                    t = time.perf_counter()
                    assert client.post("/v1/solve", json={"example": "gripper"}).status_code == 200
                    times.append(time.perf_counter() - t)
                    status = client.get(f"/v1/jobs/{job['id']}").json()
                    builder = client.get("/v1/health").json()["builder"]
                    if first_progress is None and status["progress"]["done"] > 0:
                        first_progress = time.perf_counter() - started
                    busy = builder is not None and builder["queued"] > 0  # a request stays queued while it builds
                    seen_busy = seen_busy or busy
                    if built is None and seen_busy and not busy:
                        built = time.perf_counter() - started
                    if status["status"] not in ("queued", "running") and built is not None:
                        break
                    time.sleep(0.05)
                wall = time.perf_counter() - started
        finally:
            proc.terminate()
            proc.wait(30)
    times.sort()
    p99 = statistics.quantiles(times, n=100)[98]
    print(
        f"small /v1/solve during a four-bar simulation job and its kernels' build: {len(times)} requests, "
        f"p50 {statistics.median(times) * 1e3:.1f} ms, p99 {p99 * 1e3:.1f} ms, max {times[-1] * 1e3:.1f} ms"
    )
    if first_progress is None:
        raise SystemExit(f"the job showed no progress in {wall:.0f} s: {status}")
    print(
        f"  job: first progress after {first_progress:.2f} s, {status['status']} "
        f"({status['progress']['done']}/{status['progress']['total']} windows) after {wall:.1f} s; "
        + (
            f"builder idle after {built:.1f} s"
            if built is not None
            else f"the builder still busy after 60 s: {builder}"
        )
    )


if __name__ == "__main__":
    main()
