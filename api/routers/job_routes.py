"""POST /v1/<route> for every job kind of the registry (service.jobs.kinds): 202 and a job to
follow at /v1/jobs/{id}. A route's body is the request's common fields (the document, model,
overrides, Newton options) and the kind's options model, so a kind registered with one line
is served, documented in /openapi.json and offered by the workbench's Run menu."""

# No `from __future__ import annotations`: each route's body type is made at run time and
# FastAPI reads the endpoint's annotations as objects.

from typing import Any

from fastapi import APIRouter, Response
from pydantic import ConfigDict

from flexmech.api.deps import OwnerDep, ServicesDep
from flexmech.api.documents import request_document
from flexmech.api.job_creation import JOB_LINKS, create_job
from flexmech.api.job_schemas import JobStatusResponse
from flexmech.api.parsed_route import ParsedBodyRoute
from flexmech.api.responses import JOB_ERRORS
from flexmech.api.schemas import DocumentRequest
from flexmech.service.jobs.base import JobKind
from flexmech.service.jobs.kinds import job_kinds


def request_model(kind: JobKind) -> type[DocumentRequest]:
    """The body of a kind's route: the common fields and its options (named as the kind says:
    SweepRequest, ...)."""
    namespace = {
        "__module__": __name__,
        "__doc__": kind.summary,
        "model_config": ConfigDict(extra="forbid", allow_inf_nan=False, json_schema_extra={"examples": kind.examples}),
    }
    return type(kind.request_name, (DocumentRequest, kind.Options), namespace)


def spec_of(kind: JobKind, request: DocumentRequest, document: dict[str, Any]) -> dict[str, Any]:
    """The job as stored: its document (an example's, when named), the common fields, and the
    kind's options as JSON (the kind reads them back as its typed spec)."""
    # python mode: JSON mode would turn a NaN inside a free-form field (an optimize problem) into
    # null, which the kind would then read as absent rather than refuse
    own = request.model_dump(include=set(kind.Options.model_fields), exclude_none=True)
    return {
        "document": document,
        "model": request.model,
        "overrides": request.overrides,
        "options": request.options.given() if request.options else None,
        **own,
    }


def _add_route(router: APIRouter, kind: JobKind) -> None:
    body = request_model(kind)

    async def create(request: body, services: ServicesDep, owner: OwnerDep, response: Response) -> JobStatusResponse:  # type: ignore[valid-type]
        document = request_document(request, services)
        return await create_job(kind.name, spec_of(kind, request, document), services, owner, response)

    create.__doc__ = kind.description
    router.add_api_route(
        f"/{kind.route}",
        create,
        methods=["POST"],
        operation_id=kind.operation_id,
        status_code=202,
        response_model=JobStatusResponse,
        responses={**JOB_ERRORS, 202: {"description": "The job, queued", "links": JOB_LINKS}},
        summary=kind.title,
        name=kind.operation_id,
    )


def describe(kind: JobKind) -> dict[str, Any]:
    return {
        "name": kind.name,
        "route": f"/v1/{kind.route}",
        "summary": kind.summary.rstrip("."),
        "options": kind.Options.model_json_schema(),
    }


def job_router() -> APIRouter:
    router = APIRouter(prefix="/v1", tags=["jobs"], route_class=ParsedBodyRoute)
    for kind in job_kinds().values():
        if not getattr(kind, "own_route", False):  # the analysis job takes /v1/solve's body: api.routers.solve
            _add_route(router, kind)

    @router.get("/job-kinds", operation_id="list_job_kinds", summary="The job kinds, with their options")
    async def job_kind_list() -> list[dict[str, Any]]:
        """Each kind's name, route (POST), summary and the JSON schema of its own request fields:
        what the client's `jobs` methods are made from."""
        return [describe(kind) for kind in job_kinds().values()]

    return router
