"""POST /v1/solve: one analysis of one mechanism, answered synchronously. Its body is the union
of the registered analyses' requests (api.analysis_requests), so the route is made when the
app is. GET /v1/analyses lists them with their options' and results' JSON schemas: what the
client's methods, the workbench's forms and generated clients are made from."""

# No `from __future__ import annotations`: the body's type is built at run time and FastAPI
# reads the endpoint's annotations as objects.

import json

from fastapi import APIRouter, Request, Response

from flexmech.api.analysis_requests import options_of, solve_request_type
from flexmech.api.answer_cache import REPEATABLE
from flexmech.api.deps import OwnerDep, ServicesDep
from flexmech.api.documents import request_document
from flexmech.api.parsed_route import ParsedBodyRoute
from flexmech.api.responses import ERRORS
from flexmech.api.routers.analysis_jobs import add_analysis_job_route
from flexmech.api.schemas import DocumentRequest, SolveResponse
from flexmech.service.analyses import ANALYSES, AnalysisOptions, AnalysisRequest
from flexmech.service.costs import check_report_size, check_response_bytes
from flexmech.service.requests import Limits, compile_request, newton_options
from flexmech.service.solvers.reports import plain

REPEATABLE_STATUSES = ("converged", "finished")  # a time limit's or a failure's report may differ next time


def json_bytes(report: dict) -> bytes:
    """A report as the answer's body: compact UTF-8 JSON, as FastAPI's JSONResponse writes it."""
    try:
        text = json.dumps(report, ensure_ascii=False, allow_nan=False, separators=(",", ":"))
    except (TypeError, ValueError):  # a plugin's report with numpy values or NaN: made plain first
        text = json.dumps(plain(report), ensure_ascii=False, allow_nan=False, separators=(",", ":"))
    return text.encode("utf-8")


def _solve(
    name: str, given: AnalysisOptions, request: DocumentRequest, document: dict, limits: Limits
) -> tuple[bytes, bool]:
    """In a solver worker: the analysis by name (the worker has the same registry), costed by
    the size of its report before it runs, and its report checked against its Result model and
    encoded here, so the server's event loop only passes bytes on; and whether the same request
    would give the same report (converged or finished: api.answer_cache may keep it)."""
    options = newton_options(request.options.given() if request.options else None, limits.solve_time_limit)
    mech = compile_request(document, request.model, request.overrides, limits)
    analysis = ANALYSES.named(name)
    typed = analysis.options_of(given)
    size = analysis.report_size(mech, typed)
    check_report_size(size, limits)
    report = analysis.run(mech, AnalysisRequest(options, typed))
    analysis.Result.model_validate(report)  # a report that does not fit its own model is a bug: a 500
    body = json_bytes(report)
    check_response_bytes(len(body), limits, size.pointer)
    return body, report.get("status") in REPEATABLE_STATUSES


def solve_router() -> APIRouter:
    router = APIRouter(prefix="/v1", tags=["solve"], route_class=ParsedBodyRoute)
    body = solve_request_type()

    # The report is checked against its analysis' Result model (a plugin's fields need not fit
    # SolveResponse); the OpenAPI document lists every Result model (api.analysis_requests).
    @router.post(
        "/solve",
        operation_id="solve",
        response_model=None,
        responses={**ERRORS, 200: {"model": SolveResponse, "description": "The analysis' report"}},
        summary=f"Solve one mechanism: {', '.join(ANALYSES.names())}",
    )
    async def solve(request: body, services: ServicesDep, _owner: OwnerDep, http: Request) -> Response:  # type: ignore[valid-type]
        """Runs in a solver worker (api.solver_pool). Non-convergence is a 200 with `status` and
        diagnostics; a document that cannot be modelled is a 422 naming the field; a report
        larger than the response limit is a 422 before any work, saying what to change."""
        analysis = ANALYSES.named(request.analysis)
        document = request_document(request, services)
        # the common fields travel as a plain DocumentRequest: the request's own class is made here
        common = DocumentRequest.model_construct(**{n: getattr(request, n) for n in DocumentRequest.model_fields})
        answer, repeatable = await services.solver.call(
            _solve,
            analysis.name,
            options_of(analysis, request),
            common,
            document,
            services.limits,
            time_limit=services.limits.solve_time_limit,
            large=analysis.long,
        )
        http.scope[REPEATABLE] = repeatable
        return Response(answer, media_type="application/json")

    add_analysis_job_route(router, body)

    @router.get("/analyses", operation_id="list_analyses", summary="The analyses /v1/solve runs, with their options")
    async def analyses() -> list[dict]:
        """Each analysis' name, summary, whether a sweep may run it, and the JSON schemas of its
        options (the request's own fields) and of its result."""
        return ANALYSES.describe()

    return router
