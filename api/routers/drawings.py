"""POST /v1/drawings: a mechanism drawn to scale; POST /v1/documents/parse: document text
(JSON or YAML) read into a document; POST /v1/documents/upgrade: a document of an older
shape in today's (models.documents.upgrade). The workbench page draws and edits with them."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Response
from fastapi.concurrency import run_in_threadpool

from flexmech.api.deps import OwnerDep, ServicesDep
from flexmech.api.documents import request_document
from flexmech.api.drawing_schemas import DocumentText, DocumentUpgrade, DrawingRequest, FabricationRequest
from flexmech.api.parsed_route import ParsedBodyRoute
from flexmech.api.responses import ERRORS
from flexmech.models import MechanismError
from flexmech.models.documents.reading import parse_json, parse_yaml
from flexmech.models.documents.upgrade import upgraded
from flexmech.service.analyses.equilibrium import solve_state
from flexmech.service.drawings.drawing import mechanism_drawing
from flexmech.service.drawings.path import path_frames
from flexmech.service.offers import offers
from flexmech.service.requests import Limits, compile_request, newton_options
from flexmech.service.solvers.reports import plain

router = APIRouter(prefix="/v1", tags=["workbench"], route_class=ParsedBodyRoute)


def _drawing(request: DrawingRequest, document: dict, limits: Limits) -> dict:
    mech = compile_request(document, request.model, request.overrides, limits)
    if request.state == "undeformed":  # with what the document can be asked (the page's Run menu)
        return plain({"status": "undeformed", **mechanism_drawing(mech), "offers": offers(mech)})
    options = newton_options(request.options.given() if request.options else None, limits.solve_time_limit)
    if request.state == "path":
        frames = path_frames(mech, request.path.path, request.path.values, options)
        unit = mech.doc_unit(mech.parameter_kind(request.path.path))
        cut = len(frames) < len(request.path.values)
        return plain(
            {
                "status": "time_limit" if cut else "path",
                **mechanism_drawing(mech),
                "path": request.path.path,
                "unit": unit,
                "frames": frames,
                "message": f"{len(frames)} of {len(request.path.values)} states drawn in the time limit" if cut else "",
            }
        )
    result, _ = solve_state(mech, options, None)
    drawing = mechanism_drawing(result.mechanism, result.z, result.outputs())
    return plain({"status": result.status, **drawing})


@router.post(
    "/drawings",
    operation_id="draw",
    response_model=dict[str, Any],
    responses=ERRORS,
    summary="The mechanism drawn to scale: centre lines, bodies, joints, objects, loads (document units)",
)
async def draw(request: DrawingRequest, services: ServicesDep, _owner: OwnerDep) -> dict:
    """Outlines a body carries are drawn undeformed with its name; a pose [dx, dy, rotation
    (rad)] about the body's reference point moves them. With state "equilibrium", `deformed`
    holds the deformed centre lines and every body's pose, and `status` the solve's."""
    document = request_document(request, services)
    return await services.solver.call(
        _drawing, request, document, services.limits, time_limit=services.limits.solve_time_limit
    )


def _fabrication(request: FabricationRequest, document: dict, limits: Limits) -> tuple[str, bytes]:
    from flexmech.service.drawings.fabrication import fabrication
    from flexmech.service.drawings.fabrication_files import dxf_bytes, file_stem, gds_bytes

    mech = compile_request(document, request.model, request.overrides, limits)
    drawn = fabrication(mech, request.deformed, request.chord_error)
    data = dxf_bytes(drawn) if request.format == "dxf" else gds_bytes(drawn)
    return f"{file_stem(mech.document.name)}.{request.format}", data


@router.post(
    "/drawings/fabrication",
    operation_id="draw_for_fabrication",
    response_class=Response,
    responses={
        200: {
            "description": "The DXF or GDSII file, its name in Content-Disposition",
            "content": {
                "application/dxf": {},
                "application/octet-stream": {"schema": {"type": "string", "format": "binary"}},
            },
        },
        **ERRORS,
    },
    summary="The fabricated outlines of every body and flexure as a DXF or GDSII file (document length unit)",
)
async def draw_for_fabrication(request: FabricationRequest, services: ServicesDep, _owner: OwnerDep) -> Response:
    """Layers bodies, flexures, anchors (and deformed); in GDS the layers 1 to 4 in that order."""
    document = request_document(request, services)
    name, data = await services.solver.call(
        _fabrication, request, document, services.limits, time_limit=services.limits.solve_time_limit
    )
    media = "application/dxf" if request.format == "dxf" else "application/octet-stream"
    return Response(data, media_type=media, headers={"Content-Disposition": f'attachment; filename="{name}"'})


def _parsed(request: DocumentText) -> dict:
    text = request.text
    as_json = request.format == "json" or (request.format == "auto" and text.lstrip().startswith("{"))
    document = parse_json(text) if as_json else parse_yaml(text, aliases=False)
    if not isinstance(document, dict):
        raise MechanismError("/text", f"a document is a mapping of sections, not {type(document).__name__}")
    return {"document": document, "format": "json" if as_json else "yaml"}


@router.post(
    "/documents/parse",
    operation_id="parse_document",
    response_model=dict[str, Any],
    responses=ERRORS,
    summary="Document text (JSON or YAML) read into a document",
)
async def parse_document(request: DocumentText, _owner: OwnerDep) -> dict:
    try:
        return await run_in_threadpool(_parsed, request)
    except MechanismError as exc:
        raise MechanismError("/text", exc.problem) from None


@router.post(
    "/documents/upgrade",
    operation_id="upgrade_document",
    response_model=dict[str, Any],
    responses=ERRORS,
    summary="A document of an older shape in today's, and what changed (as `flexmech upgrade`)",
)
async def upgrade_document(request: DocumentUpgrade, _owner: OwnerDep) -> dict:
    try:
        document, changes = await run_in_threadpool(upgraded, request.document)
    except MechanismError as exc:
        raise MechanismError(f"/document{exc.pointer}", exc.problem) from None
    return {"document": document, "changes": changes}
