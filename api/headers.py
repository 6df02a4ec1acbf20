"""Headers every response carries (ASGI middleware): `X-Content-Type-Options: nosniff`, so a
browser never reads a JSON answer or a script as something else, and the workbench's content
security policy on its page and on every file it loads, whichever path serves them (/, /jobs/..,
/workbench/..)."""

from __future__ import annotations

from flexmech.api.routers.workbench import POLICY

NOSNIFF = (b"x-content-type-options", b"nosniff")
CSP = (b"content-security-policy", POLICY.encode())


def serves_the_page(path: str) -> bool:
    return path == "/" or path.startswith(("/jobs/", "/workbench/"))


class SecurityHeaders:
    def __init__(self, app):
        self.app = app

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        extra = [NOSNIFF, CSP] if serves_the_page(scope.get("path", "")) else [NOSNIFF]

        async def with_headers(message):
            if message["type"] == "http.response.start":
                present = {name.lower() for name, _ in message.get("headers", [])}
                message = {
                    **message,
                    "headers": [*message.get("headers", []), *(h for h in extra if h[0] not in present)],
                }
            await send(message)

        return await self.app(scope, receive, with_headers)
