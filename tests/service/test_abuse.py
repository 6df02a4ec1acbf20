"""A live server driven through the requests that once broke it (tests/abuse_cases.py), while a
small /v1/solve runs alongside: every abusive request is answered with its 4xx naming the
field, and every small solve is answered throughout. Their times are printed, not asserted
(tests pass on a loaded machine): benchmarks/abuse_replay.py times every answer against its
2 s target, benchmarks/api_latency.py small solves beside a long run."""

from __future__ import annotations

import json
import socket
import statistics
import threading
import time

import httpx
import pytest
from abuse_cases import cases
from conftest import EXAMPLES, Deployment


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("abuse")
    server = Deployment(
        "sqlite",
        {
            "FLEXMECH_DATA_DIR": str(tmp / "data"),
            "FLEXMECH_WORKERS": "1",
            "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
            "FLEXMECH_API_KEYS": "",
            "FLEXMECH_REQUEST_READ_TIMEOUT": "1",
            "FLEXMECH_SOLVE_TIME_LIMIT": "2",
        },
        tmp,
    ).start()
    yield server
    server.stop()


class SmallSolves(threading.Thread):
    """POST /v1/solve of the gripper, over and over, timing each."""

    def __init__(self, url: str):
        super().__init__(daemon=True)
        self.url = url
        self.times: list[float] = []
        self.statuses: list[int] = []
        self.done = threading.Event()

    def run(self) -> None:
        with httpx.Client(base_url=self.url, timeout=30) as client:
            while not self.done.is_set():
                started = time.perf_counter()
                r = client.post("/v1/solve", json={"example": "gripper"})
                self.times.append(time.perf_counter() - started)
                self.statuses.append(r.status_code)
                time.sleep(0.005)


def short_body(url: str) -> tuple[int, dict, float]:
    """A request that declares 1000 bytes and sends 10, then waits: (status, body, seconds)."""
    host, port = url.removeprefix("http://").split(":")
    started = time.perf_counter()
    with socket.create_connection((host, int(port)), timeout=10) as s:
        s.sendall(
            b"POST /v1/solve HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
            b'Content-Length: 1000\r\n\r\n{"example"'
        )
        answer = b""
        while b"\r\n\r\n" not in answer or not answer.rstrip().endswith(b"}"):
            chunk = s.recv(65536)
            if not chunk:
                break
            answer += chunk
    head, _, body = answer.partition(b"\r\n\r\n")
    assert b"\r\nconnection: close" in head.lower()  # the rest of the body may come: no next request here
    return int(head.split()[1]), json.loads(body), time.perf_counter() - started


def test_abusive_requests_are_refused_while_small_solves_keep_answering(server):
    with httpx.Client(base_url=server.url, timeout=30) as client:
        assert client.post("/v1/solve", json={"example": "gripper"}).status_code == 200  # warm
    small = SmallSolves(server.url)
    small.start()
    wrong, slowest = [], (None, 0.0)
    try:
        time.sleep(0.5)
        with httpx.Client(base_url=server.url, timeout=30) as client:
            for case in cases():
                started = time.perf_counter()
                if isinstance(case.body, bytes):
                    r = client.post(case.path, content=case.body, headers={"Content-Type": "application/json"})
                else:
                    r = client.post(case.path, json=case.body)
                seconds = time.perf_counter() - started
                error = (
                    r.json().get("error", {})
                    if r.headers.get("content-type", "").startswith("application/json")
                    else {}
                )
                slowest = max(slowest, (case.name, seconds), key=lambda item: item[1])
                if (
                    r.status_code != case.status
                    or case.message not in error.get("message", "")
                    or (case.pointer is not None and error.get("pointer") != case.pointer)
                ):
                    wrong.append((case.name, r.status_code, error))
        status, body, seconds = short_body(server.url)
        if status != 408 or body["error"]["code"] != "request_timeout":
            wrong.append(("a body shorter than its Content-Length", status, body, seconds))
        time.sleep(0.5)
    finally:
        small.done.set()
        small.join(30)
    assert not wrong
    assert set(small.statuses) == {200} and len(small.times) >= 5
    p99 = statistics.quantiles(small.times, n=100)[98]
    print(
        f"\n{len(cases()) + 1} abusive requests, the slowest {slowest[0]} in {slowest[1]:.2f} s (short body "
        f"{seconds:.2f} s); small solve: {len(small.times)} requests, median "
        f"{statistics.median(small.times) * 1e3:.1f} ms, p99 {p99 * 1e3:.1f} ms"
    )
    assert "Traceback" not in server.output(tail=None)
