"""Dependencies of the routes, as Annotated aliases."""

from __future__ import annotations

import hmac
from typing import Annotated

from fastapi import Depends, Request
from fastapi.security import APIKeyHeader

from flexmech.api.errors import ApiError
from flexmech.api.state import Services

_api_key_header = APIKeyHeader(
    name="X-API-Key", auto_error=False, description="Required when the server has FLEXMECH_API_KEYS set"
)


# Both dependencies are coroutines: FastAPI runs a plain function in its thread pool, a hand-off
# that cost every request about a millisecond (two of them) for no blocking work.
async def get_services(request: Request) -> Services:
    return request.app.state.services


ServicesDep = Annotated[Services, Depends(get_services)]


async def get_owner(services: ServicesDep, api_key: Annotated[str | None, Depends(_api_key_header)]) -> str:
    """The caller's identity for job ownership; 401 when keys are on and this one is not known."""
    keys = services.settings.api_keys
    if keys:
        if not api_key:
            raise ApiError(401, "unauthorized", "missing API key: send it in the X-API-Key header")
        if not any(hmac.compare_digest(api_key.encode(), k.encode()) for k in keys):
            raise ApiError(401, "unauthorized", "API key not recognized")
    return services.owner_of(api_key)


OwnerDep = Annotated[str, Depends(get_owner)]
