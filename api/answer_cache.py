"""Answers of /v1/solve kept for the same request from the same key (ASGI middleware, inside
the body guard, which has read the whole body).

A solve is a function of its request: the document (an example's is read once, when the server
starts), the model, the overrides, the options and the analysis' fields. A design tool or the
workbench that asks the same again (a page reloaded, a design revisited) gets the same bytes
back from memory, without validation, a worker or a solve: a new gripper solve takes about 1.5 ms
of the server's interpreter, its repeat about what an unknown path's 404 takes. Only answers the route
marks as repeatable are kept (a converged or finished report, never a time limit's or an
error), at most ENTRY_BYTES each and `max_bytes` in all, least recently used first out. The key
is the request's bytes, media type and its API key's digest: one key never learns what another
asked, not even from how fast it is answered. It answers before the body is parsed (api.limits.JsonBody). A kept answer says so in `X-Flexmech-Answer: kept`.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict

CACHED_PATH = "/v1/solve"
REPEATABLE = "flexmech.repeatable"  # set in the scope by the route: this answer may be kept
RAW_BODY = "flexmech.raw_body"  # the body's bytes, left in the scope by the body guard
ENTRY_BYTES = 1_000_000  # the largest answer kept
KEPT = (b"x-flexmech-answer", b"kept")


class AnswerCache:
    def __init__(self, app, max_bytes: int):
        self.app = app
        self.max_bytes = max_bytes
        self._answers: OrderedDict[bytes, tuple[list, bytes]] = OrderedDict()  # key -> (headers, body)
        self._bytes = 0

    def _key(self, scope) -> bytes | None:
        body = scope.get(RAW_BODY)
        if self.max_bytes <= 0 or body is None or scope.get("path") != CACHED_PATH or scope.get("method") != "POST":
            return None
        headers = dict(scope.get("headers") or [])
        said = hashlib.sha256(headers.get(b"x-api-key", b"")).digest() + headers.get(b"content-type", b"")
        digest = hashlib.sha256(said + b"\0" + body)
        return digest.digest()

    async def __call__(self, scope, receive, send):
        key = self._key(scope) if scope["type"] == "http" else None
        if key is None:
            return await self.app(scope, receive, send)
        found = self._answers.get(key)
        if found is not None:
            self._answers.move_to_end(key)
            headers, body = found
            await send({"type": "http.response.start", "status": 200, "headers": [*headers, KEPT]})
            await send({"type": "http.response.body", "body": body, "more_body": False})
            return None
        started: dict = {}
        parts: list[bytes] = []

        async def keeping(message):
            if message["type"] == "http.response.start":
                started.update(message)
            elif message["type"] == "http.response.body" and started.get("status") == 200:
                parts.append(message.get("body", b""))
                if not message.get("more_body", False) and scope.get(REPEATABLE):
                    self._keep(key, list(started.get("headers", [])), b"".join(parts))
            await send(message)

        return await self.app(scope, receive, keeping)

    def _keep(self, key: bytes, headers: list, body: bytes) -> None:
        size = len(body) + len(key)
        if size > min(ENTRY_BYTES, self.max_bytes):
            return
        old = self._answers.pop(key, None)
        if old is not None:
            self._bytes -= len(old[1]) + len(key)
        self._answers[key] = (headers, body)
        self._bytes += size
        while self._bytes > self.max_bytes:
            dropped, (_, dropped_body) = self._answers.popitem(last=False)
            self._bytes -= len(dropped_body) + len(dropped)
