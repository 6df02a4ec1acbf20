"""Answers of /v1/solve kept for a repeated request (api.answer_cache): over real HTTP, the same
body from the same key is answered with the same bytes and says so; another key's identical
request is solved for that key; answers that may differ next time (a time limit's, an error) are
never kept. The bound on the kept answers' memory is checked on the middleware itself."""

from __future__ import annotations

import asyncio

import httpx
import pytest
from conftest import sqlite_server

from flexmech.api.answer_cache import CACHED_PATH, RAW_BODY, REPEATABLE, AnswerCache

KEYS = ("answer-first-key-0123", "answer-second-key-0123")
KEPT = "x-flexmech-answer"
GRIPPER = {"example": "gripper", "overrides": {"/loads/actuation/force/1": 42.5}}


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    server = sqlite_server(tmp_path_factory, "answer-cache", workers=1, keys=KEYS)
    yield server
    server.stop()


def post(server, body: dict, key: str = KEYS[0]) -> httpx.Response:
    return httpx.post(server.url + "/v1/solve", json=body, headers={"X-API-Key": key}, timeout=120)


def test_a_repeated_request_gets_the_same_answer_kept_for_its_key_only(server):
    first, again = post(server, GRIPPER), post(server, GRIPPER)
    other_key = post(server, GRIPPER, KEYS[1])
    other_load = post(server, {**GRIPPER, "overrides": {"/loads/actuation/force/1": 42.6}})
    assert first.status_code == again.status_code == other_key.status_code == 200
    assert KEPT not in first.headers and again.headers[KEPT] == "kept"
    assert again.content == first.content and again.headers["content-type"] == "application/json"
    assert again.headers["x-content-type-options"] == "nosniff"  # the outer headers still apply
    assert KEPT not in other_key.headers  # solved for that key: one key never meets another's answers
    assert KEPT not in other_load.headers
    assert other_load.json()["outputs"]["end_effector.x"] != first.json()["outputs"]["end_effector.x"]
    unauthorized = post(server, GRIPPER, "not-a-key-of-this-server")
    assert unauthorized.status_code == 401 and KEPT not in unauthorized.headers


def test_answers_that_may_differ_are_solved_again(server):
    traced = {
        "example": "snap_through_arch",
        "analysis": "trace",
        "options": {"time_limit": 0.2},
        "trace": {"path": "/loads/P/force/1", "stop": -300.0, "step": 1e-4, "max_points": 4000},
    }
    limited = [post(server, traced) for _ in range(2)]
    assert [r.json()["status"] for r in limited] == ["time_limit", "time_limit"]
    assert all(KEPT not in r.headers for r in limited)
    refused = [post(server, {**GRIPPER, "overrides": {"/loads/actuation/force/9": 1.0}}) for _ in range(2)]
    assert [r.status_code for r in refused] == [422, 422] and all(KEPT not in r.headers for r in refused)


class _Solver:
    """An app answering a body of `size` bytes per request, every answer repeatable."""

    def __init__(self, size: int):
        self.size, self.calls = size, 0

    async def __call__(self, scope, receive, send):
        self.calls += 1
        scope[REPEATABLE] = True
        await send({"type": "http.response.start", "status": 200, "headers": [(b"content-type", b"application/json")]})
        await send({"type": "http.response.body", "body": b"x" * self.size, "more_body": False})


def _ask(cache: AnswerCache, body: bytes) -> list[dict]:
    sent: list[dict] = []

    async def send(message):
        sent.append(message)

    scope = {"type": "http", "method": "POST", "path": CACHED_PATH, "headers": [], RAW_BODY: body}
    asyncio.run(cache(scope, None, send))
    return sent


def test_the_kept_answers_stay_within_their_bound_least_recently_used_out():
    app = _Solver(1000)
    cache = AnswerCache(app, max_bytes=3500)  # three answers of 1000 bytes and their keys
    for body in (b"a", b"b", b"c"):
        _ask(cache, body)
    assert app.calls == 3
    _ask(cache, b"a")  # kept: used now
    _ask(cache, b"d")  # the fourth: b, the least recently used, goes
    assert app.calls == 4 and cache._bytes <= 3500
    _ask(cache, b"a")
    _ask(cache, b"c")
    assert app.calls == 4  # both still kept
    _ask(cache, b"b")
    assert app.calls == 5  # solved again
    large = AnswerCache(_Solver(4000), max_bytes=3500)
    _ask(large, b"a")
    _ask(large, b"a")
    assert large.app.calls == 2 and large._bytes == 0  # an answer larger than the bound is never kept
