"""/v1/jobs/{id}: status and progress, result, cancel, delete. Jobs of any kind."""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

from fastapi import APIRouter, Path, Query, Response
from fastapi.concurrency import run_in_threadpool

from flexmech.api.deps import OwnerDep, ServicesDep
from flexmech.api.errors import ApiError, not_found
from flexmech.api.job_schemas import JobListResponse, JobResultResponse, JobStatusResponse, JobSummary
from flexmech.api.responses import errors
from flexmech.api.routers.usage import usage_response
from flexmech.api.store_schemas import JobDeletedResponse
from flexmech.service.jobs.kinds import job_kinds, kind_named
from flexmech.service.jobs.store import FINAL, Job

router = APIRouter(prefix="/v1/jobs", tags=["jobs"])

PAGE = MAX_PAGE = 10_000  # points in a page of a result (stored results are bounded: FLEXMECH_MAX_RESULT_VALUES)
JobId = Path(pattern=r"^[0-9a-f]{32}$", description="the id POST returned")


def job_status(job: Job) -> JobStatusResponse:
    end = job.finished_at or datetime.now(UTC)
    elapsed = (end - job.started_at).total_seconds() if job.started_at else None
    return JobStatusResponse(
        id=job.id,
        kind=job.kind,
        status=job.status,
        error=job.error,
        restarts=job.restarts,
        progress={
            "done": job.done,
            "total": job.total,
            "failed_points": job.failed_points,
            "fraction": job.done / job.total if job.total else 1.0,
        },
        timings={
            "created_at": job.created_at,
            "started_at": job.started_at,
            "finished_at": job.finished_at,
            "elapsed_seconds": elapsed,
        },
        links={
            "self": f"/v1/jobs/{job.id}",
            "result": f"/v1/jobs/{job.id}/result",
            "archive": f"/v1/jobs/{job.id}/archive" if hasattr(job_kinds().get(job.kind), "archive") else None,
        },
    )


def _owned(services, job_id: str, owner: str) -> Job:
    """The job if this caller owns it. Another key's job is 'not found', not 'forbidden', so
    ids of other users' jobs cannot be probed."""
    job = services.store.get(job_id)
    if job is None or job.owner != owner:
        raise not_found(f"no job '{job_id}'")
    return job


@router.get(
    "",
    operation_id="list_jobs",
    response_model=JobListResponse,
    responses=errors(401),
    summary="The caller's recent jobs, newest first, with status and progress",
)
async def list_jobs(
    services: ServicesDep,
    owner: OwnerDep,
    limit: int = Query(20, ge=1, le=100, description="jobs in the list"),
) -> JobListResponse:
    recent = await run_in_threadpool(services.store.recent, owner, limit)
    return JobListResponse(jobs=[JobSummary(**job_status(job).model_dump(), name=name) for job, name in recent])


@router.get(
    "/{job_id}",
    operation_id="get_job",
    response_model=JobStatusResponse,
    responses=errors(401, 404),
    summary="Status, progress and timings of a job",
)
async def get_job(services: ServicesDep, owner: OwnerDep, job_id: str = JobId) -> JobStatusResponse:
    return job_status(await run_in_threadpool(_owned, services, job_id, owner))


def _result(services, job: Job, offset: int, limit: int) -> JobResultResponse:
    kind = kind_named(job.kind)
    if not kind.paged:
        return JobResultResponse(
            id=job.id,
            kind=job.kind,
            status=job.status,
            complete=job.done == job.total,
            result=kind.result(job.spec, job.plan, services.store.points(job.id)),
        )
    points = services.store.points(job.id, offset, limit)
    page = {"offset": offset, "limit": limit, "returned": len(points), "total": job.done}
    return JobResultResponse(
        id=job.id,
        kind=job.kind,
        status=job.status,
        complete=job.done == job.total,
        page=page,
        result=kind.result(job.spec, job.plan, points),
    )


@router.get(
    "/{job_id}/result",
    operation_id="get_job_result",
    response_model=JobResultResponse,
    responses=errors(401, 404),
    summary="The job's result (the points so far while it runs), a page at a time",
)
async def get_job_result(
    services: ServicesDep,
    owner: OwnerDep,
    job_id: str = JobId,
    offset: int = Query(0, ge=0, le=10**9, description="points to skip (in index order)"),
    limit: int = Query(PAGE, ge=1, le=MAX_PAGE, description="points in the page"),
) -> Response:
    """A sweep's points come a page at a time (`page` says which; ask again with offset +
    limit while page.returned == limit); an optimization's result is whole."""
    job = await run_in_threadpool(_owned, services, job_id, owner)
    encoded = await run_in_threadpool(_encoded_result, services, job, offset, limit)
    return Response(encoded, media_type="application/json")


def _encoded_result(services, job: Job, offset: int, limit: int) -> bytes:
    """The result read, checked and encoded in a thread: a stored result may be megabytes (an
    analysis job's report), which the event loop must never validate or encode."""
    return _result(services, job, offset, limit).model_dump_json(by_alias=True).encode("utf-8")


@router.get(
    "/{job_id}/request",
    operation_id="get_job_request",
    response_model=dict[str, Any],
    responses=errors(401, 404),
    summary="What the job was asked: its document and the fields it runs with",
)
async def get_job_request(services: ServicesDep, owner: OwnerDep, job_id: str = JobId) -> dict[str, Any]:
    """The job's stored specification (the document, model, overrides and the kind's own
    fields), so a page or a tool can show the mechanism of a job it did not start."""
    job = await run_in_threadpool(_owned, services, job_id, owner)
    return {"id": job.id, "kind": job.kind, **job.spec}


def _archive(services, job: Job) -> tuple[str, bytes]:
    """The job's archive: 404 for a kind without one, 409 until it is stored."""
    make = getattr(kind_named(job.kind), "archive", None)
    if make is None:
        raise not_found(f"a {job.kind} job has no archive (an export job has)")
    found = make(job.spec, job.plan, services.store.points(job.id))
    if found is None:
        if job.status in FINAL:
            raise ApiError(409, "conflict", f"job '{job.id}' has {job.status} without an archive")
        raise ApiError(409, "conflict", f"job '{job.id}' is {job.status}: its archive comes when it has succeeded")
    return found


@router.get(
    "/{job_id}/archive",
    operation_id="get_job_archive",
    response_class=Response,
    responses={
        200: {
            "description": "The archive (.tar.gz), its file name in Content-Disposition",
            "content": {"application/gzip": {"schema": {"type": "string", "format": "binary"}}},
        },
        **errors(401, 404, 409),
    },
    summary="The job's files as a .tar.gz archive (an export's C library)",
)
async def get_job_archive(services: ServicesDep, owner: OwnerDep, job_id: str = JobId) -> Response:
    """The files of a job whose result is files (an export job: its folder, under the library's
    name); 409 while the job has not stored them."""
    job = await run_in_threadpool(_owned, services, job_id, owner)
    name, data = await run_in_threadpool(_archive, services, job)
    return Response(
        data, media_type="application/gzip", headers={"Content-Disposition": f'attachment; filename="{name}"'}
    )


def _cancel(services, job: Job) -> Job:
    """Cancel the job (409 when it has already finished); the runner stops its tasks."""
    cancelled = job.status not in FINAL and services.store.finish(job.id, "cancelled", "cancelled by the caller")
    current = services.store.get(job.id) or job
    if not cancelled:
        raise ApiError(409, "conflict", f"job '{job.id}' has already {current.status}")
    services.runner.wake()
    return current


@router.post(
    "/{job_id}/cancel",
    operation_id="cancel_job",
    response_model=JobStatusResponse,
    responses=errors(401, 404, 409),
    summary="Cancel a queued or running job (its points so far are kept)",
)
async def cancel_job(services: ServicesDep, owner: OwnerDep, job_id: str = JobId) -> JobStatusResponse:
    """Stored points are kept and stay readable at /result; DELETE removes the job."""
    job = await run_in_threadpool(_owned, services, job_id, owner)
    return job_status(await run_in_threadpool(_cancel, services, job))


def _delete(services, job: Job, owner: str) -> JobDeletedResponse:
    if job.status not in FINAL:
        services.store.finish(job.id, "cancelled", "deleted by the caller")
        services.runner.wake()
    freed = services.store.delete(job.id)
    if freed is None:  # deleted by another request (or purged) meanwhile
        raise not_found(f"no job '{job.id}'")
    return JobDeletedResponse(id=job.id, status=job.status, freed_bytes=freed, usage=usage_response(services, owner))


@router.delete(
    "/{job_id}",
    operation_id="delete_job",
    response_model=JobDeletedResponse,
    responses=errors(401, 404),
    summary="Delete a job and everything it stored (a queued or running job is cancelled first)",
)
async def delete_job(services: ServicesDep, owner: OwnerDep, job_id: str = JobId) -> JobDeletedResponse:
    """Its spec, points and archive are gone at once and their bytes count no more against
    the key's quota (its document's too, unless another of the key's jobs uses it)."""
    job = await run_in_threadpool(_owned, services, job_id, owner)
    return await run_in_threadpool(_delete, services, job, owner)
