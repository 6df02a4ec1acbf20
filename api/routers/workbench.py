"""The browser workbench: the page at / (and /jobs/{id}, the same page showing a job) and its
scripts and styles under /workbench/, all files of this package (api/web): no CDN, and no
build step but the editor's library, one committed module (api/web/vendor/codemirror.js, made
by scripts/build-editor-bundle). The page talks to the same /v1 API as any client, with the
same API keys."""

from __future__ import annotations

from pathlib import Path

from fastapi import APIRouter, FastAPI
from fastapi.responses import FileResponse, JSONResponse
from fastapi.staticfiles import StaticFiles

from flexmech.models.documents.document import MechanismDocument

WEB = Path(__file__).resolve().parents[1] / "web"
# The page loads nothing from elsewhere: the browser refuses any other origin.
POLICY = (
    "default-src 'self'; img-src 'self' data: blob:; style-src 'self' 'unsafe-inline'; "
    "script-src 'self'; connect-src 'self'; object-src 'none'; base-uri 'none'; frame-ancestors 'self'"
)
HEADERS = {"Content-Security-Policy": POLICY, "Cache-Control": "no-cache"}

router = APIRouter(include_in_schema=False)


def _page() -> FileResponse:
    return FileResponse(WEB / "index.html", media_type="text/html", headers=HEADERS)


@router.get("/")
async def workbench() -> FileResponse:
    return _page()


@router.get("/jobs/{job_id}")
async def job_page(job_id: str) -> FileResponse:
    """The page; its script reads the job id from the address and follows the job."""
    return _page()


@router.get("/workbench/document-schema.json")
async def document_schema() -> JSONResponse:
    """The JSON schema of the mechanism document (its element families as registered now):
    the editor completes field names from it."""
    return JSONResponse(MechanismDocument.model_json_schema(), headers={"Cache-Control": "no-cache"})


def mount_workbench(app: FastAPI) -> None:
    app.include_router(router)
    app.mount("/workbench", StaticFiles(directory=WEB), name="workbench")
