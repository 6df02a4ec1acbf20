"""A new structure of known element families, answered by a warm server (issue 23, point 6).

A real uvicorn (one solver worker) on an empty cache first solves each example as shipped (the
families' first use: their graphs built, "first ever"), then structures it has not seen, each
one POST /v1/solve with the document inline, timed at the client:

  renamed   every element renamed (the same structure: its graphs are shared)
  count     every link and curved beam with another number of intervals (1, 2, 3 more)
  topology  one more element of its own kinds (six_bar: a link from J1 to J3; the grippers: a
            second beam beside the first, on the same bodies)

Printed per example and variant: the answer's wall time (each of three distinct structures)
and the status. The issue asks for a first answer within 0.5 s; the machine is shared, so the
figures carry its load (the server's answers to /v1/health before the run are printed beside).

    python3 -m benchmarks.new_structures
"""

from __future__ import annotations

import copy
import json
import statistics
import time
from pathlib import Path

import httpx

from benchmarks.api_latency import served

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
# the element copied, and what changes in the copy
TOPOLOGY = {
    "six_bar": ("L1", {"from": "J1", "to": "J3", "length": 0.351204, "shape": {"type": "straight", "angle": 75.4889}}),
    "gripper_exact": ("a", {"radius": 0.21}),
    "planar_spring": None,
    "gripper": ("a", {"radius": 0.21}),
}


def renamed(doc: dict, k: int) -> dict:
    """Every element and output renamed (nothing refers to an element by name in these)."""
    out = copy.deepcopy(doc)
    out["elements"] = {f"r{k}_{name}": el for name, el in doc["elements"].items()}
    if "outputs" in doc:
        out["outputs"] = {f"r{k}_{name}": spec for name, spec in doc["outputs"].items()}
    return out


def recounted(doc: dict, k: int) -> dict:
    out = copy.deepcopy(doc)
    for el in out["elements"].values():
        if el.get("type") == "link" or el.get("model") == "exact":
            el["intervals"] = el.get("intervals", 8) + k
    return out


def extended(doc: dict, name: str, k: int) -> dict | None:
    edit = TOPOLOGY.get(name)
    if edit is None:
        return None
    source, changes = edit
    out = copy.deepcopy(doc)
    element = {**doc["elements"][source], **changes}
    if "radius" in changes:
        element["radius"] = changes["radius"] + 0.01 * k
    if k > 1:  # another structure again
        element["intervals"] = element.get("intervals", 8) + k
    out["elements"][f"extra{k}"] = element
    return out


def timed(client: httpx.Client, doc: dict) -> tuple[float, str]:
    started = time.perf_counter()
    answer = client.post("/v1/solve", json={"document": doc})
    seconds = time.perf_counter() - started
    status = answer.json().get("status", answer.status_code) if answer.status_code == 200 else answer.status_code
    return seconds, str(status)


def main() -> None:
    with served(None, empty_cache=True) as url, httpx.Client(base_url=url, timeout=120) as client:
        health = []
        for _ in range(20):
            t = time.perf_counter()
            client.get("/v1/health")
            health.append(time.perf_counter() - t)
        print(f"server floor: /v1/health p50 {1e3 * statistics.median(health):.1f} ms")
        print(f"{'example':16s} {'first ever':>12s} {'renamed':>22s} {'count':>22s} {'topology':>22s}")
        for name in TOPOLOGY:
            doc = json.loads((EXAMPLES / f"{name}.json").read_text())
            first = timed(client, doc)
            cells = []
            for make in (lambda k: renamed(doc, k), lambda k: recounted(doc, k), lambda k: extended(doc, name, k)):
                runs = [timed(client, variant) for variant in (make(k) for k in (1, 2, 3)) if variant]
                cells.append(
                    " ".join(f"{s:.2f}" for s, _ in runs)
                    + (f" ({','.join(sorted({st for _, st in runs}))})" if runs else "n/a")
                )
            print(f"{name:16s} {first[0]:8.2f} s   " + "  ".join(f"{c:>22s}" for c in cells))


if __name__ == "__main__":
    main()
