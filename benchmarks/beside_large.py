"""Small requests beside the largest analyses the limits allow (issue 47, Deliver 5): while four
clients post, again and again, the largest frequency response and the largest simulation that
/v1/solve answers, a fifth asks /v1/health and a gripper /v1/solve (each with a load never asked
before, so every one is solved) every 20 ms. Printed: both small requests' p50, p99 and max, and
what the large ones were (their size, time and status). One run, a real uvicorn with its default
settings (two solver workers: small requests keep the first).

    python3 -m benchmarks.beside_large [--seconds 30]

The largest frequency response: gripper_modes (exact curved beams with mass, 69 unknowns), three
outputs at the most points (100000): about 0.72 million numbers counted before the work, under
the 20 MB bound (four outputs are refused). The largest simulation: the rod of Lan's Example I.1
at the most elements of one link (64) for the most steps of a /v1/solve run (20000), every
output kept, as many states as an answer holds (the smallest `every` not refused): it runs into
the 10 s solve limit.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import statistics
import tempfile
import threading
import time

import httpx

from benchmarks.api_latency import ACTUATION, EXAMPLE, REPO, percentile, start_server

FREQUENCY_RESPONSE = {
    "example": "gripper_modes",
    "analysis": "frequency_response",
    "input": ACTUATION,
    "outputs": ["end_effector.x", "end_effector.y", "bodies.coupler.angle"],
    "points": 100_000,
}


def simulation(every: int) -> dict:
    document = json.loads((REPO / "examples" / "rod_free_vibration.json").read_text())
    document["elements"]["rod"]["intervals"] = 64
    document["simulate"].pop("outputs", None)  # every output
    return {"document": document, "analysis": "simulate", "simulate": {"until": 2, "step": 1e-4, "every": every}}


def largest_simulation(client: httpx.Client) -> dict:
    """The simulation keeping the most states an answer may hold: the smallest `every` that is
    not refused for its report's size (a refusal comes before any work)."""
    for every in range(1, 100):
        answer = client.post("/v1/solve", json=simulation(every))
        if answer.status_code == 200:
            return simulation(every)
        assert answer.json()["error"]["pointer"] == "/simulate/every", answer.text[:300]
    raise SystemExit("no simulation of the rod fits an answer")


def large_client(url: str, body: dict, until: float, out) -> None:
    """Post `body` until the time `until` (time.time()); put (seconds, bytes, status) of each."""
    with httpx.Client(base_url=url, timeout=120) as client:
        while time.time() < until:
            started = time.perf_counter()
            answer = client.post("/v1/solve", json=body)
            status = answer.json().get("status") if answer.status_code == 200 else f"HTTP {answer.status_code}"
            out.put((body.get("analysis"), time.perf_counter() - started, len(answer.content), status))


def probe(url: str, until: float) -> tuple[list[float], list[float], int]:
    """(health seconds, gripper solve seconds, failures) every 20 ms until `until`."""
    document = json.loads(EXAMPLE.read_text())
    health, solves, failed, k = [], [], 0, 0
    with httpx.Client(base_url=url, timeout=60) as client:
        while time.time() < until:
            started = time.perf_counter()
            failed += client.get("/v1/health").status_code != 200
            health.append(time.perf_counter() - started)
            k += 1
            body = {"document": document, "overrides": {ACTUATION: 40.0 + 1e-6 * k}}
            started = time.perf_counter()
            answer = client.post("/v1/solve", json=body)
            solves.append(time.perf_counter() - started)
            failed += answer.status_code != 200 or answer.json()["status"] != "converged"
            time.sleep(0.02)
    return health, solves, failed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=30.0)
    args = parser.parse_args()
    context = multiprocessing.get_context("spawn")  # the large clients' JSON parsing is not the probe's
    with tempfile.TemporaryDirectory() as data:
        proc, url = start_server(data)
        try:
            with httpx.Client(base_url=url, timeout=120) as client:  # every structure compiled before
                for body in (FREQUENCY_RESPONSE, {"example": "gripper"}):
                    answer = client.post("/v1/solve", json=body)
                    assert answer.status_code == 200, answer.text[:300]
                simulated = largest_simulation(client)
            bodies = [FREQUENCY_RESPONSE, FREQUENCY_RESPONSE, simulated, simulated]
            until = time.time() + args.seconds
            out = context.Queue()
            clients = [context.Process(target=large_client, args=(url, b, until, out)) for b in bodies]
            for c in clients:
                c.start()
            time.sleep(1.0)  # the large requests under way
            health, solves, failed = probe(url, until)
            for c in clients:
                c.join(180)
            large = []
            while not out.empty():
                large.append(out.get())
        finally:
            proc.terminate()
            proc.wait(30)
    ms = 1e3
    print(f"{args.seconds:g} s, four clients posting the largest analyses /v1/solve answers, a probe every 20 ms:")
    print(
        f"  (the frequency response: {len(FREQUENCY_RESPONSE['outputs'])} outputs x {FREQUENCY_RESPONSE['points']} "
        f"points; the simulation: 64 elements, 20000 steps, every {simulated['simulate']['every']} kept)"
    )
    for name in ("frequency_response", "simulate"):
        runs = [r for r in large if r[0] == name]
        if runs:
            print(
                f"  {name}: {len(runs)} answered, {statistics.median(r[1] for r in runs):.2f} s each (median), "
                f"{max(r[2] for r in runs) / 1e6:.1f} MB, statuses {sorted({r[3] for r in runs})}"
            )
    for name, times in (("GET /v1/health", health), ("gripper POST /v1/solve (a new load each)", solves)):
        print(
            f"  {name}: {len(times)} requests, p50 {statistics.median(times) * ms:.1f} ms, "
            f"p99 {percentile(times, 99) * ms:.1f} ms, max {max(times) * ms:.1f} ms (target p99 < 100 ms: "
            f"{'met' if percentile(times, 99) < 0.1 else 'NOT met'})"
        )
    print(f"  failed small requests: {failed}")


if __name__ == "__main__":
    threading.excepthook = lambda info: None  # a client's broken connection at the end is not a figure
    main()
