"""POST /v1/sweeps: a sweep job (202 and a job to follow at /v1/jobs/{id})."""

from __future__ import annotations

from fastapi import APIRouter, Response
from fastapi.concurrency import run_in_threadpool

from api.deps import OwnerDep, ServicesDep
from api.documents import request_document
from api.responses import ERRORS
from api.routers.jobs import job_status
from api.schemas import JobStatusResponse, SweepRequest
from service.jobs.kinds import kind_named

router = APIRouter(prefix="/v1", tags=["jobs"])


def sweep_spec(request: SweepRequest, document: dict) -> dict:
    return {
        "document": document,
        "model": request.model,
        "overrides": request.overrides,
        "options": request.options.given() if request.options else None,
        "parameters": [p.model_dump(exclude_none=True) for p in request.parameters],
        "grid": request.grid,
        "continuation": request.continuation,
        "outputs": request.outputs,
    }


async def create_job(kind_name: str, spec: dict, services, owner: str, response: Response) -> JobStatusResponse:
    """Validate a spec with its kind (on the solver thread: it compiles the mechanism), store the
    job and wake the runner. Any job kind goes through here."""
    kind = kind_named(kind_name)
    plan = await services.solver.call(kind.prepare, spec, services.limits)
    job = await run_in_threadpool(services.store.create, kind_name, owner, spec, plan.meta, plan.total)
    services.runner.wake()
    response.status_code = 202
    response.headers["Location"] = f"/v1/jobs/{job.id}"
    return job_status(job)


# OpenAPI links: what a generated client (or schemathesis' stateful tests) can do with the new job
JOB_LINKS = {
    name: {"operationId": operation, "parameters": {"job_id": "$response.body#/id"}}
    for name, operation in (("GetJob", "get_job"), ("GetJobResult", "get_job_result"), ("CancelJob", "cancel_job"))
}


@router.post("/sweeps", operation_id="create_sweep", status_code=202, response_model=JobStatusResponse,
             responses={**ERRORS, 202: {"description": "The job, queued", "links": JOB_LINKS}},
             summary="Start a sweep job")
async def create_sweep(request: SweepRequest, services: ServicesDep, owner: OwnerDep,
                       response: Response) -> JobStatusResponse:
    """Every point is stored as soon as its task finishes; follow the job at /v1/jobs/{id} and
    read the points at /v1/jobs/{id}/result (also while it runs)."""
    document = request_document(request, services)
    return await create_job("sweep", sweep_spec(request, document), services, owner, response)
