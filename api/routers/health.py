"""GET /v1/health: liveness for load balancers and container health checks (no key needed);
"degraded" (still 200: requests are answered) while the kernel builder is down."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from fastapi import APIRouter
from fastapi.concurrency import run_in_threadpool
from sqlalchemy.engine import make_url

from flexmech.api.deps import ServicesDep
from flexmech.api.store_schemas import HealthReport, StoreTotals

router = APIRouter(prefix="/v1", tags=["health"])


def _version() -> str:
    try:
        return version("flexmech")
    except PackageNotFoundError:
        return "unknown"


def _store_totals(services) -> StoreTotals:
    quotas = services.settings.quotas()
    return StoreTotals(
        **services.store.totals(),
        per_key={"max_jobs": quotas.max_jobs, "max_bytes": quotas.max_bytes, "max_running": quotas.max_running},
        retention_seconds=services.settings.job_retention.total_seconds(),
    )


@router.get("/health", operation_id="health", response_model=HealthReport, summary="Is the service up")
async def health(services: ServicesDep) -> HealthReport:
    """Up or degraded, and what the job store holds against the quotas (for the operator)."""
    store = await run_in_threadpool(_store_totals, services)
    builder = services.builder.state() if services.builder is not None else None
    return HealthReport(
        status="degraded" if builder is not None and not builder["running"] else "ok",
        version=_version(),
        database=make_url(services.store.url).get_backend_name(),
        executor=services.executor.description,
        active_jobs=store.running,
        builder=builder,
        store=store,
    )
