"""POST /v1/impact-studies: seed 004's parametric study as a job (202, then /v1/jobs/{id}):
the nominal impact simulation and each chosen field moved up and down by its step, run on
the pool or Dask, compared quantity by quantity."""

from __future__ import annotations

from fastapi import APIRouter, Response

from api.deps import OwnerDep, ServicesDep
from api.documents import request_document
from api.impact_study_schemas import ImpactStudyRequest
from api.job_creation import JOB_LINKS, create_job
from api.job_schemas import JobStatusResponse
from api.parsed_route import ParsedBodyRoute
from api.responses import ERRORS

router = APIRouter(prefix="/v1", tags=["jobs"], route_class=ParsedBodyRoute)


@router.post(
    "/impact-studies",
    operation_id="create_impact_study",
    status_code=202,
    response_model=JobStatusResponse,
    responses={**ERRORS, 202: {"description": "The job, queued", "links": JOB_LINKS}},
    summary="Start a parametric study of an impact simulation",
)
async def create_impact_study(
    request: ImpactStudyRequest, services: ServicesDep, owner: OwnerDep, response: Response
) -> JobStatusResponse:
    """Each run is stored as it finishes; the result ranks the fields by how early they change the motion."""
    document = request_document(request, services)
    spec = {
        "document": document,
        "model": request.model,
        "overrides": request.overrides,
        "simulate": request.simulate,
        "study": request.study.model_dump(),
    }
    return await create_job("impact_study", spec, services, owner, response)
