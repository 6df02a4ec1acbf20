"""POST /v1/sweeps: a sweep job (202 and a job to follow at /v1/jobs/{id})."""

from __future__ import annotations

from fastapi import APIRouter, Response

from api.deps import OwnerDep, ServicesDep
from api.documents import request_document
from api.job_creation import JOB_LINKS, create_job
from api.job_schemas import JobStatusResponse, SweepRequest
from api.parsed_route import ParsedBodyRoute
from api.responses import ERRORS

router = APIRouter(prefix="/v1", tags=["jobs"], route_class=ParsedBodyRoute)


def sweep_spec(request: SweepRequest, document: dict) -> dict:
    return {
        "document": document,
        "model": request.model,
        "overrides": request.overrides,
        "options": request.options.given() if request.options else None,
        "parameters": [p.model_dump(exclude_none=True) for p in request.parameters],
        "grid": request.grid,
        "continuation": request.continuation,
        "until": request.until.model_dump() if request.until else None,
        "outputs": request.outputs,
        "analysis": request.analysis,
    }


@router.post(
    "/sweeps",
    operation_id="create_sweep",
    status_code=202,
    response_model=JobStatusResponse,
    responses={**ERRORS, 202: {"description": "The job, queued", "links": JOB_LINKS}},
    summary="Start a sweep job",
)
async def create_sweep(
    request: SweepRequest, services: ServicesDep, owner: OwnerDep, response: Response
) -> JobStatusResponse:
    """Every point is stored as soon as its task finishes; follow the job at /v1/jobs/{id} and
    read the points at /v1/jobs/{id}/result (also while it runs)."""
    document = request_document(request, services)
    return await create_job("sweep", sweep_spec(request, document), services, owner, response)
