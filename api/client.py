"""Python client of the flexmech HTTP API: sync (`Client`) and async (`AsyncClient`).

Needs only httpx and pydantic; it imports neither CasADi nor FastAPI, so a design tool can
install it light (`pip install ./api`). Requests are checked against the same schemas the
server uses before they are sent, and responses come back as those schemas' models.

    with Client("http://127.0.0.1:8000", api_key=...) as flexmech:
        answer = flexmech.solve(example="gripper", overrides={"/loads/actuation/force/1": 50})
        job = flexmech.sweep(example="gripper",
                             parameters=[{"path": "/loads/actuation/force/1", "start": 0, "stop": 60, "steps": 200}],
                             continuation="/loads/actuation/force/1")
        flexmech.wait(job.id, progress=lambda s: print(s.progress.done, "/", s.progress.total))
        points = flexmech.result(job.id).result.points
"""

from __future__ import annotations

import asyncio
import time
from typing import Any

import httpx
from pydantic import TypeAdapter

from flexmech.api.analysis_methods import Analyses
from flexmech.api.client_support import (
    FlexmechError,
    JobTimeout,
    Progress,
    bytes_of,
    finished,
    headers,
    page,
    parse,
    request_body,
    where,
)
from flexmech.api.drawing_schemas import DrawingRequest
from flexmech.api.job_schemas import (
    ContactPathRequest,
    ExportRequest,
    ImpactStudyRequest,
    JobListResponse,
    JobRequest,
    JobResultResponse,
    JobStatusResponse,
    OptimizeRequest,
    SimulationRequest,
    SweepRequest,
)
from flexmech.api.schemas import AnalysisReport, ExampleSummary, SolveRequest, SolveResponse
from flexmech.api.store_schemas import HealthReport, JobDeletedResponse, UsageResponse

__all__ = ["AsyncClient", "Client", "FlexmechError", "JobTimeout"]

_EXAMPLES = TypeAdapter(list[ExampleSummary])


class Client:
    """Synchronous client. `transport` lets tests pass an httpx transport."""

    def __init__(
        self,
        base_url: str | None = None,
        api_key: str | None = None,
        timeout: float = 60.0,
        transport: httpx.BaseTransport | None = None,
    ):
        url, key = where(base_url, api_key)
        self._http = httpx.Client(base_url=url, headers=headers(key), timeout=timeout, transport=transport)
        self._analyze: Analyses | None = None
        self._jobs: Analyses | None = None

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        self._http.close()

    def health(self) -> HealthReport:
        return parse(self._http.get("/v1/health"), HealthReport)

    def usage(self) -> UsageResponse:
        """This key's stored jobs, running jobs and bytes against its quotas."""
        return parse(self._http.get("/v1/usage"), UsageResponse)

    def examples(self) -> list[ExampleSummary]:
        return parse(self._http.get("/v1/examples"), _EXAMPLES)

    def example(self, name: str) -> dict:
        return parse(self._http.get(f"/v1/examples/{name}"), dict)

    def solve(self, request: SolveRequest | None = None, **fields: Any) -> SolveResponse:
        """One analysis; fields as in SolveRequest (document or example, analysis, overrides, ...)
        and the analysis' own options (see `analyses()`, or call it as `analyze.<name>(...)`)."""
        return parse(self._http.post("/v1/solve", json=request_body(SolveRequest, request, fields)), SolveResponse)

    def _report(self, **fields: Any) -> AnalysisReport:
        return parse(self._http.post("/v1/solve", json=request_body(SolveRequest, None, fields)), AnalysisReport)

    def job_kinds(self) -> list[dict]:
        """The server's job kinds: name, route, summary and their options' JSON schema."""
        return parse(self._http.get("/v1/job-kinds"), list)

    @property
    def jobs(self) -> Analyses:
        """A method per job kind of the server (`jobs.sweep(example="gripper", parameters=[...])`),
        its options as keyword arguments, documented from its schema; each returns the new
        job's status."""
        if self._jobs is None:
            routes = {kind["name"]: kind["route"] for kind in self.job_kinds()}

            def start(kind: str, **fields: Any) -> JobStatusResponse:
                body = request_body(JobRequest, None, fields)
                return parse(self._http.post(routes[kind], json=body), JobStatusResponse)

            self._jobs = Analyses(self.job_kinds, start, "job kind", "the new job's status (JobStatusResponse)")
        return self._jobs

    def analyses(self) -> list[dict]:
        """The server's analyses: name, summary, sweepable, and their options' and results'
        JSON schemas."""
        return parse(self._http.get("/v1/analyses"), list)

    @property
    def analyze(self) -> Analyses:
        """A method per analysis of the server (`analyze.equilibrium(example="gripper",
        stiffness=True)`), its options as keyword arguments, documented from its schema."""
        if self._analyze is None:
            self._analyze = Analyses(self.analyses, lambda name, **fields: self._report(analysis=name, **fields))
        return self._analyze

    def sweep(self, request: SweepRequest | None = None, **fields: Any) -> JobStatusResponse:
        """Start a sweep job; fields as in SweepRequest. Returns the new job's status."""
        return parse(self._http.post("/v1/sweeps", json=request_body(SweepRequest, request, fields)), JobStatusResponse)

    def optimize(self, request: OptimizeRequest | None = None, **fields: Any) -> JobStatusResponse:
        """Start an optimization job; fields as in OptimizeRequest. Returns the new job's status."""
        return parse(
            self._http.post("/v1/optimize", json=request_body(OptimizeRequest, request, fields)), JobStatusResponse
        )

    def contact_path(self, request: ContactPathRequest | None = None, **fields: Any) -> JobStatusResponse:
        """Start a contact path job; fields as in ContactPathRequest. Returns the new job's status."""
        return parse(
            self._http.post("/v1/contacts", json=request_body(ContactPathRequest, request, fields)), JobStatusResponse
        )

    def simulation(self, request: SimulationRequest | None = None, **fields: Any) -> JobStatusResponse:
        """Start a simulation job; fields as in SimulationRequest. Returns the new job's status."""
        return parse(
            self._http.post("/v1/simulations", json=request_body(SimulationRequest, request, fields)),
            JobStatusResponse,
        )

    def impact_study(self, request: ImpactStudyRequest | None = None, **fields: Any) -> JobStatusResponse:
        """Start a parametric study of an impact simulation; fields as in ImpactStudyRequest."""
        return parse(
            self._http.post("/v1/impact-studies", json=request_body(ImpactStudyRequest, request, fields)),
            JobStatusResponse,
        )

    def export(self, request: ExportRequest | None = None, **fields: Any) -> JobStatusResponse:
        """Start an export of the mechanism's solver as a C99 library; fields as in ExportRequest
        (document or example, model, name, inputs, outputs, ranges, target {output, equals, by},
        max_iterations, tolerance). Its archive: `export_archive(job.id)`."""
        return parse(
            self._http.post("/v1/exports", json=request_body(ExportRequest, request, fields)), JobStatusResponse
        )

    def archive(self, job_id: str) -> bytes:
        """The job's archive (.tar.gz bytes); FlexmechError 409 while it is not stored."""
        return bytes_of(self._http.get(f"/v1/jobs/{job_id}/archive"))

    def export_archive(self, job_id: str, timeout: float | None = None, poll: float = 0.2) -> bytes:
        """Wait for an export job, then its archive (.tar.gz bytes); FlexmechError if it failed."""
        self.wait(job_id, timeout, poll)
        return self.archive(job_id)

    def drawing(self, request: DrawingRequest | None = None, **fields: Any) -> dict:
        """The mechanism drawn to scale as data; fields as in DrawingRequest (state
        undeformed, equilibrium or path)."""
        return parse(self._http.post("/v1/drawings", json=request_body(DrawingRequest, request, fields)), dict)

    def upgrade_document(self, document: dict) -> dict:
        """{document: in today's shape, changes: what changed} for a document of an older shape."""
        return parse(self._http.post("/v1/documents/upgrade", json={"document": document}), dict)

    def job(self, job_id: str) -> JobStatusResponse:
        return parse(self._http.get(f"/v1/jobs/{job_id}"), JobStatusResponse)

    def recent_jobs(self, limit: int = 20) -> JobListResponse:
        """This key's newest jobs first, with status, progress and the document's name."""
        return parse(self._http.get("/v1/jobs", params={"limit": limit}), JobListResponse)

    def job_request(self, job_id: str) -> dict:
        """What the job was asked: its document and fields."""
        return parse(self._http.get(f"/v1/jobs/{job_id}/request"), dict)

    def result(self, job_id: str, offset: int = 0, limit: int | None = None) -> JobResultResponse:
        """The job's result; a sweep's points a page at a time (offset, limit: at most 10,000)."""
        return parse(self._http.get(f"/v1/jobs/{job_id}/result", params=page(offset, limit)), JobResultResponse)

    def cancel(self, job_id: str) -> JobStatusResponse:
        """Stop a queued or running job; its points so far stay readable."""
        return parse(self._http.post(f"/v1/jobs/{job_id}/cancel"), JobStatusResponse)

    def delete(self, job_id: str) -> JobDeletedResponse:
        """Delete a job and all it stored (cancelled first if it runs): its bytes are freed."""
        return parse(self._http.delete(f"/v1/jobs/{job_id}"), JobDeletedResponse)

    def wait(
        self, job_id: str, timeout: float | None = None, poll: float = 0.2, progress: Progress | None = None
    ) -> JobStatusResponse:
        """Poll until the job has finished (succeeded, failed or cancelled) and return its
        status. progress(status) is called after every poll. JobTimeout after `timeout` s."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while not finished(status := self.job(job_id), deadline, progress):
            time.sleep(poll)
        return status


class AsyncClient:
    """The same calls, awaitable."""

    def __init__(
        self,
        base_url: str | None = None,
        api_key: str | None = None,
        timeout: float = 60.0,
        transport: httpx.AsyncBaseTransport | None = None,
    ):
        url, key = where(base_url, api_key)
        self._http = httpx.AsyncClient(base_url=url, headers=headers(key), timeout=timeout, transport=transport)

    async def __aenter__(self) -> AsyncClient:
        return self

    async def __aexit__(self, *exc) -> None:
        await self.aclose()

    async def aclose(self) -> None:
        await self._http.aclose()

    async def health(self) -> HealthReport:
        return parse(await self._http.get("/v1/health"), HealthReport)

    async def usage(self) -> UsageResponse:
        return parse(await self._http.get("/v1/usage"), UsageResponse)

    async def examples(self) -> list[ExampleSummary]:
        return parse(await self._http.get("/v1/examples"), _EXAMPLES)

    async def example(self, name: str) -> dict:
        return parse(await self._http.get(f"/v1/examples/{name}"), dict)

    async def solve(self, request: SolveRequest | None = None, **fields: Any) -> SolveResponse:
        body = request_body(SolveRequest, request, fields)
        return parse(await self._http.post("/v1/solve", json=body), SolveResponse)

    async def analyses(self) -> list[dict]:
        """The server's analyses (as Client.analyses)."""
        return parse(await self._http.get("/v1/analyses"), list)

    async def analyzer(self) -> Analyses:
        """A method per analysis of the server, each returning a coroutine of its report:
        `(await client.analyzer()).equilibrium(example="gripper")`."""
        listing = await self.analyses()

        async def report(**fields: Any) -> AnalysisReport:
            body = request_body(SolveRequest, None, fields)
            return parse(await self._http.post("/v1/solve", json=body), AnalysisReport)

        return Analyses(lambda: listing, lambda name, **fields: report(analysis=name, **fields))

    async def sweep(self, request: SweepRequest | None = None, **fields: Any) -> JobStatusResponse:
        body = request_body(SweepRequest, request, fields)
        return parse(await self._http.post("/v1/sweeps", json=body), JobStatusResponse)

    async def optimize(self, request: OptimizeRequest | None = None, **fields: Any) -> JobStatusResponse:
        body = request_body(OptimizeRequest, request, fields)
        return parse(await self._http.post("/v1/optimize", json=body), JobStatusResponse)

    async def contact_path(self, request: ContactPathRequest | None = None, **fields: Any) -> JobStatusResponse:
        body = request_body(ContactPathRequest, request, fields)
        return parse(await self._http.post("/v1/contacts", json=body), JobStatusResponse)

    async def simulation(self, request: SimulationRequest | None = None, **fields: Any) -> JobStatusResponse:
        body = request_body(SimulationRequest, request, fields)
        return parse(await self._http.post("/v1/simulations", json=body), JobStatusResponse)

    async def impact_study(self, request: ImpactStudyRequest | None = None, **fields: Any) -> JobStatusResponse:
        body = request_body(ImpactStudyRequest, request, fields)
        return parse(await self._http.post("/v1/impact-studies", json=body), JobStatusResponse)

    async def export(self, request: ExportRequest | None = None, **fields: Any) -> JobStatusResponse:
        body = request_body(ExportRequest, request, fields)
        return parse(await self._http.post("/v1/exports", json=body), JobStatusResponse)

    async def archive(self, job_id: str) -> bytes:
        return bytes_of(await self._http.get(f"/v1/jobs/{job_id}/archive"))

    async def export_archive(self, job_id: str, timeout: float | None = None, poll: float = 0.2) -> bytes:
        await self.wait(job_id, timeout, poll)
        return await self.archive(job_id)

    async def drawing(self, request: DrawingRequest | None = None, **fields: Any) -> dict:
        return parse(await self._http.post("/v1/drawings", json=request_body(DrawingRequest, request, fields)), dict)

    async def upgrade_document(self, document: dict) -> dict:
        return parse(await self._http.post("/v1/documents/upgrade", json={"document": document}), dict)

    async def job(self, job_id: str) -> JobStatusResponse:
        return parse(await self._http.get(f"/v1/jobs/{job_id}"), JobStatusResponse)

    async def recent_jobs(self, limit: int = 20) -> JobListResponse:
        return parse(await self._http.get("/v1/jobs", params={"limit": limit}), JobListResponse)

    async def job_request(self, job_id: str) -> dict:
        return parse(await self._http.get(f"/v1/jobs/{job_id}/request"), dict)

    async def result(self, job_id: str, offset: int = 0, limit: int | None = None) -> JobResultResponse:
        return parse(await self._http.get(f"/v1/jobs/{job_id}/result", params=page(offset, limit)), JobResultResponse)

    async def cancel(self, job_id: str) -> JobStatusResponse:
        return parse(await self._http.post(f"/v1/jobs/{job_id}/cancel"), JobStatusResponse)

    async def delete(self, job_id: str) -> JobDeletedResponse:
        return parse(await self._http.delete(f"/v1/jobs/{job_id}"), JobDeletedResponse)

    async def wait(
        self, job_id: str, timeout: float | None = None, poll: float = 0.2, progress: Progress | None = None
    ) -> JobStatusResponse:
        deadline = None if timeout is None else time.monotonic() + timeout
        while not finished(status := await self.job(job_id), deadline, progress):
            await asyncio.sleep(poll)
        return status
