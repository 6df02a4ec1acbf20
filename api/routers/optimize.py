"""POST /v1/optimize: an optimization job (202 and a job to follow at /v1/jobs/{id})."""

from __future__ import annotations

from fastapi import APIRouter, Response

from api.deps import OwnerDep, ServicesDep
from api.documents import request_document
from api.job_creation import JOB_LINKS, create_job
from api.job_schemas import JobStatusResponse, OptimizeRequest
from api.parsed_route import ParsedBodyRoute
from api.responses import ERRORS

router = APIRouter(prefix="/v1", tags=["jobs"], route_class=ParsedBodyRoute)


@router.post(
    "/optimize",
    operation_id="create_optimization",
    status_code=202,
    response_model=JobStatusResponse,
    responses={**ERRORS, 202: {"description": "The job, queued", "links": JOB_LINKS}},
    summary="Start an optimization job",
)
async def create_optimization(
    request: OptimizeRequest, services: ServicesDep, owner: OwnerDep, response: Response
) -> JobStatusResponse:
    """Each start is a point of the job, stored when it finishes; the result (at
    /v1/jobs/{id}/result) is the best feasible start with its multipliers, iterations and
    history, or status infeasible with how far each constraint stays from its bounds."""
    document = request_document(request, services)
    spec = {"document": document, "model": request.model, "overrides": request.overrides, "problem": request.problem}
    return await create_job("optimize", spec, services, owner, response)
