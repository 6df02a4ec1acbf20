"""Creating a job of any kind: validated by its kind (in a solver worker: it compiles the
mechanism), stored, and the runner woken; and the OpenAPI links a new job carries."""

from __future__ import annotations

from fastapi import Response
from fastapi.concurrency import run_in_threadpool

from flexmech.api.job_schemas import JobStatusResponse
from flexmech.api.routers.jobs import job_status
from flexmech.service.jobs.kinds import kind_named
from flexmech.service.jobs.quotas import check_admission

# OpenAPI links: what a generated client (or schemathesis' stateful tests) can do with the new job
JOB_LINKS = {
    name: {"operationId": operation, "parameters": {"job_id": "$response.body#/id"}}
    for name, operation in (
        ("GetJob", "get_job"),
        ("GetJobResult", "get_job_result"),
        ("CancelJob", "cancel_job"),
        ("DeleteJob", "delete_job"),
    )
}


async def create_job(kind_name: str, spec: dict, services, owner: str, response: Response) -> JobStatusResponse:
    """202 and the job's status, its Location header pointing at it; 429 (QuotaExceeded) when
    the key's quotas have no room for it."""
    kind = kind_named(kind_name)
    quotas = services.store.quotas
    if quotas is not None:  # refused before a worker prepares it; the store checks again as it stores
        check_admission(await run_in_threadpool(services.store.usage, owner), quotas, 0)
    plan = await services.solver.call(kind.prepare, spec, services.limits, time_limit=services.limits.solve_time_limit)
    rest = {name: value for name, value in spec.items() if name != "document"}  # the document is kept apart, once
    job = await run_in_threadpool(
        services.store.create, kind_name, owner, rest, plan.meta, plan.total, spec["document"]
    )
    services.runner.wake()
    response.status_code = 202
    response.headers["Location"] = f"/v1/jobs/{job.id}"
    return job_status(job)
