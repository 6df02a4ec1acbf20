"""The request body, guarded before the app sees it (ASGI middleware).

- Size: counted as it arrives, so a chunked request without Content-Length is stopped too (413).
- Time: the whole body must arrive within read_timeout seconds; a client that declares more
  than it sends no longer holds a connection forever (408).
- JSON (JsonBody, inside the answer cache): parsed once with the document reader's bounds (models.documents.reading): nesting deeper
  than 64 levels or an integer of thousands of digits is malformed_json (400), a key given
  twice in one object is duplicate_key (422: the text is JSON, its meaning is not), never a
  merged object, a recursion error or a 500. A small body parses on the loop, a larger one on
  one thread beside it, a large one in a parser process (api.body_parsing: its duplicate check
  is Python, 0.26 s for a megabyte of small objects, which on the loop held every other
  request, /v1/health included), and the routes take the parsed value from the scope
  (api.parsed_route) instead of parsing the body again on the loop.
Bodies are small (the limit is about a megabyte), so holding one in memory is fine.
"""

from __future__ import annotations

import asyncio
import time

from flexmech.api.answer_cache import RAW_BODY
from flexmech.api.body_parsing import parse_body
from flexmech.api.errors import error_response
from flexmech.api.parsed_route import PARSED_BODY

_WITH_BODY = {"POST", "PUT", "PATCH"}

CLOSE = {"connection": "close"}  # an answer given before the whole body was read


def is_json(content_type: bytes | None) -> bool:
    """Whether a body is read as JSON: no media type, application/json or any +json type, in
    any letter case and with any parameters (as the app's own body reader takes them)."""
    if content_type is None:
        return True
    media = content_type.split(b";", 1)[0].strip().lower()
    return media == b"application/json" or media.endswith(b"+json")


class BodySizeLimit:
    def __init__(self, app, max_bytes: int, read_timeout: float = 10.0):
        self.app = app
        self.max_bytes = max_bytes
        self.read_timeout = read_timeout

    def _too_large(self, size: str):
        return error_response(
            413,
            "body_too_large",
            f"request body of {size} bytes is over the limit of {self.max_bytes} bytes",
            headers=CLOSE,
        )

    async def _read(self, scope, receive, send) -> bytes | None:
        """The whole body, or None when an error was answered (or the client went away)."""
        chunks, size = [], 0
        deadline = time.monotonic() + self.read_timeout
        while True:
            try:
                message = await asyncio.wait_for(receive(), max(deadline - time.monotonic(), 0.0))
            except TimeoutError:
                # the rest of the body may still come: the connection cannot carry another request
                await error_response(
                    408,
                    "request_timeout",
                    f"the request body did not arrive within {self.read_timeout:g} s",
                    headers=CLOSE,
                )(scope, receive, send)
                return None
            if message["type"] != "http.request":  # the client went away
                return None
            chunks.append(message.get("body", b""))
            size += len(chunks[-1])
            if size > self.max_bytes:
                await self._too_large(f"more than {self.max_bytes}")(scope, receive, send)
                return None
            if not message.get("more_body", False):
                return b"".join(chunks)

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        headers = dict(scope.get("headers") or [])
        declared = headers.get(b"content-length")
        if declared is not None and declared.isdigit() and int(declared) > self.max_bytes:
            return await self._too_large(str(int(declared)))(scope, receive, send)
        body = await self._read(scope, receive, send)
        if body is None:
            return
        scope[RAW_BODY] = body  # for the answer cache's key (api.answer_cache) and JsonBody
        replayed = False

        async def replay():
            nonlocal replayed
            if not replayed:
                replayed = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()

        return await self.app(scope, replay, send)


class JsonBody:
    """The body the guard has read, parsed as JSON (off the event loop when large) into the scope
    for the routes (api.parsed_route); a duplicate key is a 422, malformed JSON a 400. Inside the
    answer cache: a kept answer is given without parsing its request again."""

    def __init__(self, app):
        self.app = app

    async def __call__(self, scope, receive, send):
        body = scope.get(RAW_BODY) if scope["type"] == "http" else None
        headers = dict(scope.get("headers") or []) if body is not None else {}
        if body and body.strip() and scope.get("method") in _WITH_BODY and is_json(headers.get(b"content-type")):
            kind, value = await parse_body(body)
            if kind == "duplicate_key":
                return await error_response(
                    422, "duplicate_key", f"the body gives the key '{value}' twice in one object"
                )(scope, receive, send)
            if kind == "malformed_json":
                return await error_response(400, "malformed_json", value)(scope, receive, send)
            scope[PARSED_BODY] = value
        return await self.app(scope, receive, send)
