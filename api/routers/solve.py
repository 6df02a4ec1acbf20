"""POST /v1/solve: one analysis of one mechanism, answered synchronously."""

from __future__ import annotations

from fastapi import APIRouter

from api.deps import OwnerDep, ServicesDep
from api.documents import request_document
from api.parsed_route import ParsedBodyRoute
from api.responses import ERRORS
from api.schemas import SolveRequest, SolveResponse
from service.analyses import ANALYSES, AnalysisRequest
from service.requests import Limits, compile_request, newton_options

router = APIRouter(prefix="/v1", tags=["solve"], route_class=ParsedBodyRoute)

# The request fields an analysis may read (the rest say which mechanism and how to solve it).
ANALYSIS_FIELDS = ("target", "stiffness", "sensitivities", "at", "displacements", "penetrating_start", "motion",
                   "thesis_recovery", "simulate", "trace")
# Analyses that may run for seconds: they never take the worker kept for small requests.
LONG_ANALYSES = frozenset({"trace", "contact", "simulate"})


def _solve(request: SolveRequest, document: dict, limits: Limits) -> dict:
    analysis = ANALYSES.named(request.analysis)
    options = newton_options(request.options.given() if request.options else None, limits.solve_time_limit)
    mech = compile_request(document, request.model, request.overrides, limits)
    return analysis.run(mech, AnalysisRequest(options, request.model_dump(include=set(ANALYSIS_FIELDS))))


@router.post("/solve", operation_id="solve", response_model=SolveResponse, responses=ERRORS,
             summary="Solve one mechanism: equilibrium, linearization, trace, inverse, energy, contact, simulate")
async def solve(request: SolveRequest, services: ServicesDep, _owner: OwnerDep) -> dict:
    """Runs in a solver worker (api.solver_pool). Non-convergence is a 200 with `status` and
    diagnostics; a document that cannot be modelled is a 422 naming the field."""
    document = request_document(request, services)
    return await services.solver.call(_solve, request, document, services.limits,
                                      time_limit=services.limits.solve_time_limit,
                                      large=request.analysis in LONG_ANALYSES)
