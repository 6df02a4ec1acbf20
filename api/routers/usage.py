"""GET /v1/usage: what the calling key stores against its quotas (service.jobs.quotas)."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.concurrency import run_in_threadpool

from flexmech.api.deps import OwnerDep, ServicesDep
from flexmech.api.responses import errors
from flexmech.api.store_schemas import UsageResponse
from flexmech.service.jobs.quotas import FREE_HINT

router = APIRouter(prefix="/v1", tags=["jobs"])


def usage_response(services, owner: str) -> UsageResponse:
    """The key's jobs, running jobs and bytes against its quotas (without keys: the service's)."""
    used = services.store.usage(owner).against(services.settings.quotas())
    retention = services.settings.job_retention.total_seconds()
    return UsageResponse(**used, retention_seconds=retention, free=FREE_HINT["bytes"])


@router.get(
    "/usage",
    operation_id="get_usage",
    response_model=UsageResponse,
    responses=errors(401),
    summary="What this key stores against its quotas, and how long jobs are kept",
)
async def get_usage(services: ServicesDep, owner: OwnerDep) -> UsageResponse:
    """Jobs stored, jobs queued or running, and bytes stored, each with its limit; over a
    quota a new job is refused with 429 until jobs are deleted (DELETE /v1/jobs/{id})."""
    return await run_in_threadpool(usage_response, services, owner)
