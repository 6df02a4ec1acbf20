"""Does the event loop stay free while clients send large bodies? `/v1/health` latency while
eight clients (each its own process and keep-alive connection) post 0.9 MB request bodies back
to back, against a real uvicorn server.

Two bodies, both under the size limit: a solve request whose document has a 0.9 MB
`description` (one long string: a light parse, then a 422 on the request's thread, as a description
is at most 20,000 characters), and one whose document carries some ten thousand materials (many
small objects: a heavy parse, and a heavy compile), which is solved. The prober sends one health
request every 20 ms from its own process and prints p50, p99 and max, first on an idle server,
then under each load (the target: p99 < 100 ms).

    python3 -m benchmarks.body_load [--clients 8] [--seconds 10] [--url URL]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import time

import httpx
import numpy as np

from benchmarks.api_latency import EXAMPLE, served

TARGET_P99_MS = 100.0
BODY_BYTES = 900_000


def long_description_body() -> bytes:
    document = json.loads(EXAMPLE.read_text())
    document["description"] = "x" * (BODY_BYTES - len(json.dumps(document)) - 200)
    return json.dumps({"document": document, "overrides": {"/loads/actuation/force/1": 50.0}}).encode()


def many_materials_body() -> bytes:
    document = json.loads(EXAMPLE.read_text())
    material = next(iter(document["materials"].values()))
    k = 0
    while len(json.dumps(document)) < BODY_BYTES - 200:
        document["materials"].update({f"m{k + i}": material for i in range(500)})
        k += 500
    return json.dumps({"document": document}).encode()


def sender(url: str, body: bytes, stop_at: float, counts) -> None:
    with httpx.Client(base_url=url, timeout=60, headers={"content-type": "application/json"}) as client:
        while time.time() < stop_at:
            status = client.post("/v1/solve", content=body).status_code
            with counts.get_lock():
                counts[min(status // 100, 5)] += 1


def probe(url: str, seconds: float) -> list[float]:
    times = []
    with httpx.Client(base_url=url, timeout=30) as client:
        stop_at = time.time() + seconds
        while time.time() < stop_at:
            t = time.perf_counter()
            client.get("/v1/health").raise_for_status()
            times.append(time.perf_counter() - t)
            time.sleep(0.02)
    return times


def under_load(url: str, body: bytes | None, clients: int, seconds: float) -> tuple[list[float], list[int]]:
    counts = mp.Array("l", 6)
    stop_at = time.time() + seconds + 1.0
    senders = [mp.Process(target=sender, args=(url, body, stop_at, counts)) for _ in range(clients if body else 0)]
    for s in senders:
        s.start()
    time.sleep(1.0 if senders else 0.0)  # the senders connected and sending
    times = probe(url, seconds)
    for s in senders:
        s.join()
    return times, list(counts)


def report(label: str, times: list[float], counts: list[int]) -> None:
    ms = np.array(times) * 1e3
    p99 = float(np.percentile(ms, 99))
    answers = ", ".join(f"{k}xx: {n}" for k, n in enumerate(counts) if n)
    print(
        f"  {label:<34} health p50 {np.percentile(ms, 50):6.1f} ms  p99 {p99:6.1f} ms  max {ms.max():6.1f} ms"
        f"  ({len(ms)} probes; {'met' if p99 < TARGET_P99_MS else 'NOT met'})"
        + (f"  bodies answered {answers}" if answers else "")
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clients", type=int, default=8)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--url", default=None, help="a running server (default: start one)")
    args = parser.parse_args()
    bodies = {"0.9 MB description": long_description_body(), "0.9 MB of materials": many_materials_body()}
    with served(args.url) as url:
        print(
            f"/v1/health every 20 ms for {args.seconds:g} s; {args.clients} clients posting bodies back to back "
            f"(target p99 < {TARGET_P99_MS:g} ms)"
        )
        report("idle", *under_load(url, None, 0, args.seconds))
        for label, body in bodies.items():
            report(f"{label}, {len(body) / 1e6:.2f} MB", *under_load(url, body, args.clients, args.seconds))


if __name__ == "__main__":
    main()
