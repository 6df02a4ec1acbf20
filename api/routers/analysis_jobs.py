"""POST /v1/analysis-jobs: the body of /v1/solve run as a job (service.jobs.analysis), for a
report larger than an answer may be (the 422 of /v1/solve says so) or a run longer than its time
limit. A route of its own, not one of api.routers.job_routes: its body is /v1/solve's union over
the analyses, which only the solve route's maker has."""

# No `from __future__ import annotations`: the body's type is built at run time and FastAPI
# reads the endpoint's annotations as objects.

from typing import Any

from fastapi import APIRouter, Response

from flexmech.api.analysis_requests import options_of
from flexmech.api.deps import OwnerDep, ServicesDep
from flexmech.api.documents import request_document
from flexmech.api.job_creation import JOB_LINKS, create_job
from flexmech.api.job_schemas import JobStatusResponse
from flexmech.api.responses import JOB_ERRORS
from flexmech.service.analyses import ANALYSES
from flexmech.service.jobs.kinds import kind_named


def add_analysis_job_route(router: APIRouter, body: Any) -> None:
    """The route on `router`, its body `body` (api.analysis_requests.solve_request_type)."""
    kind = kind_named("analysis")

    @router.post(
        f"/{kind.route}",
        operation_id=kind.operation_id,
        status_code=202,
        response_model=JobStatusResponse,
        responses={**JOB_ERRORS, 202: {"description": "The job, queued", "links": JOB_LINKS}},
        summary=kind.title,
    )
    async def analysis_job(
        request: body,  # type: ignore[valid-type]
        services: ServicesDep,
        owner: OwnerDep,
        response: Response,
    ) -> JobStatusResponse:
        """The body of /v1/solve, run as a job: for a report larger than an answer may be (the
        422 of /v1/solve says so) or a run longer than its time limit. Its report is at
        /v1/jobs/{id}/result under `report`, bounded by what a job stores."""
        analysis = ANALYSES.named(request.analysis)
        document = request_document(request, services)
        settings = options_of(analysis, request).model_dump(mode="json", exclude_none=True)
        spec = {
            "document": document,
            "model": request.model,
            "overrides": request.overrides,
            "options": request.options.given() if request.options else None,
            "analysis": analysis.name,
            "settings": settings,
        }
        return await create_job(kind.name, spec, services, owner, response)
