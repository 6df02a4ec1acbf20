"""uvicorn's HTTP protocol with a deadline for a request's headers.

uvicorn times a connection out only while it idles after an answer (keep-alive). A client that
connects and sends nothing, or a few bytes of headers and then nothing, held its connection
(and a file descriptor) forever: the app sees nothing until the headers are complete, so no
middleware can help. Here every connection gets `FLEXMECH_HEADER_READ_TIMEOUT` seconds from
connecting, and again from each answer, to complete its next request's headers; past it the
answer is 408 `request_timeout` and the connection closes. The body has its own deadline
(`FLEXMECH_REQUEST_READ_TIMEOUT`, api.limits). Bytes of a next request that arrive together
with the previous one (pipelined) are left to keep-alive's timeout, which closes the connection
quietly. `flexmech serve` names this class to uvicorn.
"""

from __future__ import annotations

import asyncio
import json
from functools import cache

from uvicorn.protocols.http.auto import AutoHTTPProtocol


@cache
def header_seconds() -> float:
    from flexmech.service.settings import Settings

    return Settings().header_read_timeout


def _late_answer(seconds: float) -> bytes:
    body = json.dumps(
        {
            "error": {
                "status": 408,
                "code": "request_timeout",
                "message": (
                    f"the request's headers did not arrive within {seconds:g} s (FLEXMECH_HEADER_READ_TIMEOUT)"
                ),
                "pointer": None,
            }
        }
    ).encode()
    return (
        b"HTTP/1.1 408 Request Timeout\r\ncontent-type: application/json\r\nx-content-type-options: nosniff\r\n"
        b"connection: close\r\ncontent-length: " + str(len(body)).encode() + b"\r\n\r\n" + body
    )


class HeaderTimeoutProtocol(AutoHTTPProtocol):  # type: ignore[misc, valid-type]
    def connection_made(self, transport: asyncio.Transport) -> None:
        super().connection_made(transport)
        self._headers_due: asyncio.TimerHandle | None = None
        self._cycle_before = None
        self._await_headers()

    def _await_headers(self) -> None:
        if self._headers_due is None:
            self._cycle_before = self.cycle
            self._headers_due = self.loop.call_later(header_seconds(), self._headers_late)

    def _between_requests(self) -> bool:
        return self.cycle is None or self.cycle.response_complete

    def data_received(self, data: bytes) -> None:
        if self._between_requests():
            self._await_headers()  # the next request's first bytes (idling before them is keep-alive's business)
        super().data_received(data)
        if self._headers_due is not None and self.cycle is not self._cycle_before:
            self._headers_due.cancel()  # a new request's headers are complete
            self._headers_due = None

    def connection_lost(self, exc: Exception | None) -> None:
        if self._headers_due is not None:
            self._headers_due.cancel()
            self._headers_due = None
        super().connection_lost(exc)

    def _headers_late(self) -> None:
        self._headers_due = None
        if self.transport.is_closing() or not self._between_requests():
            return
        self.transport.write(_late_answer(header_seconds()))
        self.transport.close()
