"""GET /v1/health: liveness for load balancers and container health checks (no key needed);
"degraded" (still 200: requests are answered) while the kernel builder is down."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from fastapi import APIRouter
from fastapi.concurrency import run_in_threadpool
from sqlalchemy.engine import make_url

from flexmech.api.deps import ServicesDep
from flexmech.api.schemas import HealthResponse

router = APIRouter(prefix="/v1", tags=["health"])


def _version() -> str:
    try:
        return version("flexmech")
    except PackageNotFoundError:
        return "unknown"


@router.get("/health", operation_id="health", response_model=HealthResponse, summary="Is the service up")
async def health(services: ServicesDep) -> HealthResponse:
    active = await run_in_threadpool(services.store.active)
    builder = services.builder.state() if services.builder is not None else None
    return HealthResponse(
        status="degraded" if builder is not None and not builder["running"] else "ok",
        version=_version(),
        database=make_url(services.store.url).get_backend_name(),
        executor=services.executor.description,
        active_jobs=len(active),
        builder=builder,
    )
