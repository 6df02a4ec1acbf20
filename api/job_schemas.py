"""Schemas of the API's jobs as the client sees them: the envelope of a request (each kind's
own fields are the server's: service.jobs), a job's status and its result. Only pydantic here, like api.schemas (the client imports it)."""

from __future__ import annotations

from datetime import datetime
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from flexmech.api.schemas import ContactPairOut, DocumentRequest, PointStatus, ResponseModel

JobStatusName = Literal["queued", "running", "succeeded", "failed", "cancelled"]


# --- requests -------------------------------------------------------------------------------
class JobRequest(DocumentRequest):
    """A job's request as the client sends it: the kind's own fields beside the common ones,
    which the server checks against the kind's options model (GET /v1/job-kinds lists them;
    /openapi.json has each route's request)."""

    model_config = ConfigDict(extra="allow")


# The client's names for the requests of the built-in kinds (their fields: the server's schema).
SweepRequest = ContactPathRequest = OptimizeRequest = SimulationRequest = ImpactStudyRequest = ExportRequest = (
    JobRequest
)


# --- responses ------------------------------------------------------------------------------
class JobLinks(BaseModel):
    self: str
    result: str
    archive: str | None = Field(None, description="the result's files as .tar.gz (an export's C library)")


class JobProgress(BaseModel):
    done: int
    total: int
    failed_points: int = Field(description="points stored without a converged equilibrium")
    fraction: float


class JobTimings(BaseModel):
    created_at: datetime
    started_at: datetime | None
    finished_at: datetime | None
    elapsed_seconds: float | None = Field(description="since it started (until it finished)")


class JobStatusResponse(BaseModel):
    id: str
    kind: str
    status: JobStatusName
    progress: JobProgress
    timings: JobTimings
    error: str | None = None
    restarts: int = Field(0, description="times the job was taken up again after a server restart")
    links: JobLinks

    @property
    def finished(self) -> bool:
        return self.status in ("succeeded", "failed", "cancelled")


class JobSummary(JobStatusResponse):
    name: str = Field("", description="the name of the job's mechanism document")


class JobListResponse(BaseModel):
    jobs: list[JobSummary] = Field(description="the caller's newest jobs first")


class SweepParameterOut(BaseModel):
    path: str
    unit: str
    values: list[float]


class SweepPoint(ResponseModel):
    index: int
    values: list[float]
    status: PointStatus
    message: str = ""
    iterations: int
    residual_norm: float | None = Field(description="the largest unbalanced force (residual_unit), as /v1/solve")
    residual_moment: float | None = None
    solver_residual: float | None = None
    seconds: float
    outputs: dict[str, float | None]


class SweepResult(BaseModel):
    parameters: list[SweepParameterOut]
    grid: Literal["cartesian", "zip"]
    continuation: str | None
    output_units: dict[str, str]
    residual_unit: str
    residual_moment_unit: str | None = None
    analysis: str = "equilibrium"
    until: dict[str, Any] | None = Field(
        None, description="with until: its output, value, and the parameter's value found (path, value, unit)"
    )
    points: list[SweepPoint]


class ContactStateOut(ResponseModel):
    index: int
    values: list[float]
    status: PointStatus
    message: str = ""
    iterations: int
    seconds: float
    pairs: dict[str, ContactPairOut]
    outputs: dict[str, float | None]


class ContactPathResult(BaseModel):
    parameters: list[SweepParameterOut]
    output_units: dict[str, str]
    force_unit: str
    length_unit: str
    points: list[ContactStateOut]


class ResultPage(BaseModel):
    offset: int
    limit: int
    returned: int = Field(description="points in this page")
    total: int = Field(description="points stored so far")


class JobResultResponse(BaseModel):
    id: str
    kind: str
    status: JobStatusName
    complete: bool = Field(description="every point is stored; otherwise the points so far")
    page: ResultPage | None = Field(None, description="for results that list points: which of them this is")
    result: SweepResult | ContactPathResult | dict[str, Any]
