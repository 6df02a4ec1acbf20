"""POST /v1/simulations: a time simulation job (202 and a job to follow at /v1/jobs/{id}),
stored per time window. A short simulation is also POST /v1/solve with analysis "simulate":
the job's request is the simulate analysis' options (one model, service.analyses.simulate)."""

from __future__ import annotations

from fastapi import APIRouter, Response
from pydantic import ConfigDict

from api.deps import OwnerDep, ServicesDep
from api.documents import request_document
from api.job_creation import JOB_LINKS, create_job
from api.job_schemas import JobStatusResponse
from api.parsed_route import ParsedBodyRoute
from api.responses import ERRORS
from api.schemas import DocumentRequest
from api.simulation_schemas import SIMULATION_EXAMPLES
from service.analyses.simulate import SimulateOptions

router = APIRouter(prefix="/v1", tags=["jobs"], route_class=ParsedBodyRoute)


class SimulationRequest(DocumentRequest, SimulateOptions):
    """A job: a time simulation by the document's `simulate` section (with `simulate` over
    it), stored per time window as it runs."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, json_schema_extra={"examples": SIMULATION_EXAMPLES})


@router.post(
    "/simulations",
    operation_id="create_simulation",
    status_code=202,
    response_model=JobStatusResponse,
    responses={**ERRORS, 202: {"description": "The job, queued", "links": JOB_LINKS}},
    summary="Start a simulation job",
)
async def create_simulation(
    request: SimulationRequest, services: ServicesDep, owner: OwnerDep, response: Response
) -> JobStatusResponse:
    """Every time window is stored as soon as it is integrated; read them at /v1/jobs/{id}/result."""
    document = request_document(request, services)
    spec = {
        "document": document,
        "model": request.model,
        "overrides": request.overrides,
        "options": request.options.given() if request.options else None,
        "simulate": request.simulate.model_dump(exclude_none=True) if request.simulate else None,
    }
    return await create_job("simulation", spec, services, owner, response)
