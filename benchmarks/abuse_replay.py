"""Issue 24's reproductions and the abusive requests of tests/abuse_cases.py (issues 12 and 24)
replayed against a live `flexmech serve`: for each, the status it got (against the one it must get),
the seconds to the answer, and how much the resident memory of the server and every process
it started (solver workers, job pool, kernel builder) grew over it.

Before the replay the server is warmed the way it would be in use (a gripper solve, an impact
simulation on the large lane, a sweep job), so the growth shown is what each request adds.
Targets: every answer within 2 s, no growth over 200 MB.

    python3 -m benchmarks.abuse_replay
"""

from __future__ import annotations

import os
import socket
import sqlite3
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import httpx
import psutil

from benchmarks.api_latency import start_server
from benchmarks.body_load import long_description_body
from tests.abuse_cases import cases as abuse_cases

REPO = Path(__file__).resolve().parents[1]
ANSWER_WITHIN = 2.0  # s
GROWTH_UNDER = 200.0  # MB
SETTINGS = {
    "FLEXMECH_HEADER_READ_TIMEOUT": "1",
    "FLEXMECH_REQUEST_READ_TIMEOUT": "1",
    "FLEXMECH_EXAMPLES_DIR": str(REPO / "examples"),
}


@dataclass
class Case:
    name: str
    expected: int
    send: object  # (url) -> (status, bytes of the answer)


def post(path: str, body=None, raw: bytes | None = None, media: str = "application/json"):
    def send(url: str):
        if raw is not None:
            r = httpx.post(url + path, content=raw, headers={"Content-Type": media}, timeout=60)
        else:
            r = httpx.post(url + path, json=body, timeout=60)
        return r.status_code, len(r.content), r

    return send


def run_until(example: str, route: str, **simulate) -> object:
    body = {"example": example, "simulate": simulate}
    return post(route, {**body, "analysis": "simulate"} if route == "/v1/solve" else body)


def socket_exchange(payload: bytes):
    """Send payload and read until the server closes the connection."""

    def send(url: str):
        host, port = url.removeprefix("http://").split(":")
        with socket.create_connection((host, int(port)), timeout=30) as s:
            s.sendall(payload)
            answer = b""
            while chunk := s.recv(65536):
                answer += chunk
        return int(answer.split()[1]), len(answer), None

    return send


def page_headers(url: str):
    r = httpx.get(url + "/workbench/index.html", timeout=30)
    ok = "content-security-policy" in r.headers and r.headers.get("x-content-type-options") == "nosniff"
    return (r.status_code if ok else 599), len(r.content), r


def long_name(url: str):
    r = httpx.post(
        url + "/v1/solve",
        json={"example": "gripper", "overrides": {f"/elements/{'n' * 100_000}/radius": 1}},
        timeout=30,
    )
    return (r.status_code if len(r.content) < 2000 else 599), len(r.content), r


def moreau_second(url: str):
    """Not an abuse any more: a second of Moreau steps at 1e-5 s answers a bounded report."""
    r = httpx.post(
        url + "/v1/solve",
        json={"example": "csfh", "analysis": "simulate", "simulate": {"scheme": "moreau", "step": 1e-5, "until": 1.0}},
        timeout=60,
    )
    return (r.status_code if len(r.content) < 2_000_000 else 599), len(r.content), r


def large_body(url: str):
    r = httpx.post(
        url + "/v1/solve", content=long_description_body(), headers={"Content-Type": "application/json"}, timeout=60
    )
    return r.status_code, len(r.content), r


def locked_store(data_dir: Path):
    def send(url: str):
        lock = sqlite3.connect(data_dir / "flexmech.db", timeout=60, isolation_level=None)
        lock.execute("BEGIN EXCLUSIVE")
        try:
            r = httpx.post(
                url + "/v1/sweeps",
                json={"example": "gripper", "parameters": [{"path": "/loads/actuation/force/1", "values": [1.0, 2.0]}]},
                timeout=60,
            )
        finally:
            lock.execute("COMMIT")
            lock.close()
        return (r.status_code if "retry-after" in r.headers else 599), len(r.content), r

    return send


def blank_keys() -> tuple[int, float, str]:
    """(exit code, seconds, last line) of `flexmech serve` with FLEXMECH_API_KEYS=" "."""
    started = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "flexmech.api.cli", "serve", "--port", "1"],
        capture_output=True,
        text=True,
        env={**os.environ, "FLEXMECH_API_KEYS": " "},
        timeout=60,
        cwd=REPO,
    )
    return done.returncode, time.perf_counter() - started, done.stderr.strip().splitlines()[-1]


def reproductions(data_dir: Path) -> list[Case]:
    dup = b'{"example": "gripper", "example": "gripper_nylon"}'
    return [
        *[
            Case(
                f"until 1e300 step 1e-300: {example} {scheme or ''} {route}",
                422,
                run_until(example, route, until=1e300, step=1e-300, **({"scheme": scheme} if scheme else {})),
            )
            for example, scheme in (("rod_free_vibration", None), ("csfh", "moreau"), ("csfh", "event_driven"))
            for route in ("/v1/solve", "/v1/simulations")
        ],
        Case("1 s of Moreau at 1e-5 s (report under 2 MB)", 200, moreau_second),
        Case("Application/JSON with a duplicate key", 422, post("/v1/solve", raw=dup, media="Application/JSON")),
        Case("/workbench/index.html carries CSP and nosniff", 200, page_headers),
        Case("headers never finished", 408, socket_exchange(b"POST /v1/solve HTTP/1.1\r\nHost: x\r\nContent-Ty")),
        Case(
            "a body shorter than its Content-Length",
            408,
            socket_exchange(
                b"POST /v1/solve HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 1000\r\n\r\n{"
            ),
        ),
        Case("a 100,000-character name (answer under 2 kB)", 422, long_name),
        Case("a 0.9 MB description (at most 20,000 characters: refused at the door)", 422, large_body),
        Case("a locked job store (503 with Retry-After)", 503, locked_store(data_dir)),
    ]


def abuse_case_list() -> list[Case]:
    out = []
    for case in abuse_cases():
        raw = case.body if isinstance(case.body, bytes) else None
        out.append(Case(f"abuse case: {case.name}", case.status, post(case.path, None if raw else case.body, raw)))
    return out


def tree_rss(pid: int) -> float:
    """MB resident in the server and every process it started."""
    root = psutil.Process(pid)
    total = 0
    for proc in [root, *root.children(recursive=True)]:
        try:
            total += proc.memory_info().rss
        except psutil.NoSuchProcess:
            pass
    return total / 1e6


def warm(url: str) -> None:
    httpx.post(url + "/v1/solve", json={"example": "gripper"}, timeout=120).raise_for_status()
    httpx.post(
        url + "/v1/solve", json={"example": "csfh", "analysis": "simulate", "simulate": {"until": 0.1}}, timeout=120
    ).raise_for_status()
    job = httpx.post(
        url + "/v1/sweeps",
        json={"example": "gripper", "parameters": [{"path": "/loads/actuation/force/1", "values": [1.0, 2.0]}]},
        timeout=120,
    ).json()
    for _ in range(600):
        if httpx.get(f"{url}/v1/jobs/{job['id']}", timeout=30).json()["status"] in ("succeeded", "failed"):
            break
        time.sleep(0.1)


def main() -> None:
    code, seconds, line = blank_keys()
    print(f"FLEXMECH_API_KEYS=' ': flexmech serve exits {code} after {seconds:.2f} s: {line}")
    with tempfile.TemporaryDirectory() as data_dir:
        proc, url = start_server(data_dir, SETTINGS)
        try:
            warm(url)
            rows, slow, grown, wrong = [], 0, 0, 0
            for case in reproductions(Path(data_dir)) + abuse_case_list():
                before = tree_rss(proc.pid)
                started = time.perf_counter()
                status, size, _ = case.send(url)
                seconds = time.perf_counter() - started
                growth = tree_rss(proc.pid) - before
                name = case.name if len(case.name) <= 60 else case.name[:40] + f"...({len(case.name)} characters)"
                rows.append((name, status, case.expected, seconds, growth, size))
                slow += seconds > ANSWER_WITHIN
                grown += growth > GROWTH_UNDER
                wrong += status != case.expected
            width = max(len(r[0]) for r in rows)
            print(f"{'case':<{width}}  status (expected)  seconds  RSS growth (MB)  answer (bytes)")
            for name, status, expected, seconds, growth, size in rows:
                print(f"{name:<{width}}  {status} ({expected})        {seconds:7.3f}  {growth:15.1f}  {size:14d}")
            print(
                f"{len(rows)} cases: {wrong} with another status, {slow} over {ANSWER_WITHIN:g} s (slowest "
                f"{max(r[3] for r in rows):.2f} s), {grown} growing over {GROWTH_UNDER:g} MB (largest "
                f"{max(r[4] for r in rows):.1f} MB); server tree {tree_rss(proc.pid):.0f} MB at the end"
            )
        finally:
            proc.terminate()
            proc.wait(15)


if __name__ == "__main__":
    main()
