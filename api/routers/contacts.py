"""POST /v1/contacts: a contact path job (202 and a job to follow at /v1/jobs/{id}). One
contact state is POST /v1/solve with analysis "contact"."""

from __future__ import annotations

from fastapi import APIRouter, Response

from api.deps import OwnerDep, ServicesDep
from api.documents import request_document
from api.job_creation import JOB_LINKS, create_job
from api.job_schemas import ContactPathRequest, JobStatusResponse
from api.parsed_route import ParsedBodyRoute
from api.responses import ERRORS

router = APIRouter(prefix="/v1", tags=["jobs"], route_class=ParsedBodyRoute)


@router.post(
    "/contacts",
    operation_id="create_contact_path",
    status_code=202,
    response_model=JobStatusResponse,
    responses={**ERRORS, 202: {"description": "The job, queued", "links": JOB_LINKS}},
    summary="Start a contact path job",
)
async def create_contact_path(
    request: ContactPathRequest, services: ServicesDep, owner: OwnerDep, response: Response
) -> JobStatusResponse:
    """Every state is stored as soon as it is solved; read them at /v1/jobs/{id}/result."""
    document = request_document(request, services)
    spec = {
        "document": document,
        "model": request.model,
        "overrides": request.overrides,
        "options": request.options.given() if request.options else None,
        "path": [p.model_dump(exclude_none=True) for p in request.path] if request.path else None,
        "outputs": request.outputs,
        "penetrating_start": request.penetrating_start,
    }
    return await create_job("contact", spec, services, owner, response)
