"""POST /v1/solve: one analysis of one mechanism, answered synchronously."""

from __future__ import annotations

from fastapi import APIRouter

from api.deps import OwnerDep, ServicesDep
from api.documents import request_document
from api.responses import ERRORS
from api.schemas import SolveRequest, SolveResponse
from service.analysis import (
    Limits,
    compile_request,
    equilibrium_report,
    inverse_report,
    linearization_report,
    newton_options,
)

router = APIRouter(prefix="/v1", tags=["solve"])


def _solve(request: SolveRequest, document: dict, limits: Limits) -> dict:
    options = newton_options(request.options.given() if request.options else None, limits.solve_time_limit)
    mech = compile_request(document, request.model, request.overrides, limits)
    if request.analysis == "inverse":
        return inverse_report(mech, request.displacements or {})
    if request.analysis == "linearization":
        return linearization_report(mech, options, request.at)
    target = request.target.model_dump() if request.target else None
    sensitivities = request.sensitivities.model_dump() if request.sensitivities else None
    return equilibrium_report(mech, options, request.stiffness, target, sensitivities)


@router.post("/solve", operation_id="solve", response_model=SolveResponse, responses=ERRORS,
             summary="Solve one mechanism: equilibrium, inverse or linearization")
async def solve(request: SolveRequest, services: ServicesDep, _owner: OwnerDep) -> dict:
    """Runs in the server process. Non-convergence is a 200 with `status` and diagnostics; a
    document that cannot be modelled is a 422 naming the field."""
    document = request_document(request, services)
    return await services.solver.call(_solve, request, document, services.limits)
