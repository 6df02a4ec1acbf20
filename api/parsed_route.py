"""Routes that take a JSON body parsed before them: the body guard (api.limits) parses it off
the event loop, with the document reader's bounds, and leaves the value in the request's scope;
FastAPI then validates that value instead of calling json.loads on the loop a second time."""

from __future__ import annotations

from typing import Any

from fastapi import Request
from fastapi.routing import APIRoute

PARSED_BODY = "flexmech.parsed_body"


class _ParsedRequest(Request):
    async def json(self) -> Any:
        if PARSED_BODY in self.scope:
            return self.scope[PARSED_BODY]
        return await super().json()


class ParsedBodyRoute(APIRoute):
    def get_route_handler(self):
        handler = super().get_route_handler()

        async def with_parsed_body(request: Request):
            return await handler(_ParsedRequest(request.scope, request.receive))

        return with_parsed_body
