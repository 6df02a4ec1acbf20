"""Creating a job of any kind: validated by its kind (in a solver worker: it compiles the
mechanism), stored, and the runner woken; and the OpenAPI links a new job carries."""

from __future__ import annotations

from fastapi import Response
from fastapi.concurrency import run_in_threadpool

from flexmech.api.job_schemas import JobStatusResponse
from flexmech.api.routers.jobs import job_status
from flexmech.service.jobs.kinds import kind_named

# OpenAPI links: what a generated client (or schemathesis' stateful tests) can do with the new job
JOB_LINKS = {
    name: {"operationId": operation, "parameters": {"job_id": "$response.body#/id"}}
    for name, operation in (("GetJob", "get_job"), ("GetJobResult", "get_job_result"), ("CancelJob", "cancel_job"))
}


async def create_job(kind_name: str, spec: dict, services, owner: str, response: Response) -> JobStatusResponse:
    """202 and the job's status, its Location header pointing at it."""
    kind = kind_named(kind_name)
    plan = await services.solver.call(kind.prepare, spec, services.limits, time_limit=services.limits.solve_time_limit)
    job = await run_in_threadpool(services.store.create, kind_name, owner, spec, plan.meta, plan.total)
    services.runner.wake()
    response.status_code = 202
    response.headers["Location"] = f"/v1/jobs/{job.id}"
    return job_status(job)
