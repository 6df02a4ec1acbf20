"""Request and response schemas of the API's jobs (sweeps, contact paths, optimizations): what
starts one, its status and its result. Only pydantic here, like api.schemas (the client imports it)."""

from __future__ import annotations

from datetime import datetime
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from api.schemas import ContactPairOut, DocumentRequest, PointStatus, RequestModel, ResponseModel

JobStatusName = Literal["queued", "running", "succeeded", "failed", "cancelled"]


# --- requests -------------------------------------------------------------------------------
class SweepParameter(RequestModel):
    """A numeric field's values: listed, or start to stop in equal steps (stop left out when the
    sweep has `until`: the value found is the stop)."""

    path: str = Field(pattern=r"^/", max_length=256, description="JSON pointer of a numeric field")
    values: list[float] | None = Field(None, min_length=1, description="document units")
    start: float | None = Field(None, description="document units")
    stop: float | None = Field(None, description="document units (with `until`: found)")
    steps: int | None = Field(None, ge=1, description="equal steps: steps + 1 values")

    @model_validator(mode="after")
    def _values_or_range(self):
        ranged = (self.start, self.steps)
        if self.values is not None and any(v is not None for v in (*ranged, self.stop)):
            raise ValueError("give values, or start, stop and steps, not both")
        if self.values is None and any(v is None for v in ranged):
            raise ValueError("give values, or start, stop and steps")
        return self


class SweepUntil(RequestModel):
    """Sweep until an output reaches a value: the value of the (one, ranged) parameter at which
    it does is found first (as the equilibrium's target), and is the sweep's stop."""

    output: str = Field(max_length=128, description="the output", examples=["end_effector.x"])
    equals: float = Field(description="its value, in its document unit")


class SweepRequest(DocumentRequest):
    """A job: numeric fields varied over a grid, each point an equilibrium (or a sweepable analysis)."""

    model_config = ConfigDict(
        json_schema_extra={
            "examples": [
                {
                    "example": "gripper",
                    "continuation": "/loads/actuation/force/1",
                    "outputs": ["end_effector.x"],
                    "parameters": [{"path": "/loads/actuation/force/1", "start": -60, "stop": 60, "steps": 20}],
                },
                # grids that once broke the service, answered 422 now (schemathesis sends every example)
                {
                    "example": "gripper",
                    "parameters": [{"path": "/loads/actuation/force/1", "start": 0, "stop": 1, "steps": 1_000_000_000}],
                },
                {
                    "example": "gripper",
                    "parameters": [{"path": "/loads/actuation/force/1", "start": 0, "stop": 1, "steps": 10**30}],
                },
                {
                    "example": "gripper",
                    "parameters": [
                        {"path": p, "start": 0.1, "stop": 0.2, "steps": 65535}
                        for p in (
                            "/loads/actuation/force/0",
                            "/loads/actuation/force/1",
                            "/sections/flexure/h",
                            "/sections/flexure/b",
                        )
                    ],
                },
                {"example": "gripper", "parameters": [{"path": "/elements/a/radius", "values": [0.2, 0, -1]}]},
                {"example": "gripper", "parameters": [{"path": "/elements/a/arc_angle", "values": [400]}]},
            ]
        }
    )

    parameters: list[SweepParameter] = Field(
        min_length=1, max_length=8, json_schema_extra={"document_default": "/sweep"}
    )
    grid: Literal["cartesian", "zip"] = "cartesian"
    continuation: str | None = Field(
        None,
        description="path of the swept parameter that is a load path: solved in order, "
        "each point from the previous one",
        json_schema_extra={"document_default": "/sweep/path"},
    )
    until: SweepUntil | None = Field(
        None,
        description="stop where an output reaches a value (one ranged parameter)",
        json_schema_extra={"document_default": "/sweep/until"},
    )
    outputs: list[str] | None = Field(None, min_length=1, description="outputs to keep (default: all)")
    analysis: str = Field(
        "equilibrium",
        min_length=1,
        max_length=64,
        pattern=r"^[a-z_]+$",
        description="the analysis of every point (a sweepable one the schema lists)",
    )


class ContactPathRequest(DocumentRequest):
    """A job: a quasi-static contact path (fields changing together, state after state, each
    from the one before); without `path`, the document's contacts.path."""

    model_config = ConfigDict(
        json_schema_extra={
            "examples": [
                {"example": "gripper_jaw_contact"},
                {
                    "example": "gripper_jaw_contact",
                    "outputs": ["contacts.insertion.force_x"],
                    "path": [{"path": "/contacts/objects/fixture/centre/0", "start": 78, "stop": 50, "steps": 28}],
                },
                {
                    "example": "gripper_jaw_contact",
                    "path": [{"path": "/contacts/objects/fixture/centre/0", "start": 78, "stop": 50, "steps": 10**12}],
                },
            ]
        }
    )

    path: list[SweepParameter] | None = Field(
        None,
        min_length=1,
        max_length=8,
        description="fields that change together along the path",
        json_schema_extra={"document_default": "/contacts/path/parameters/0"},
    )
    outputs: list[str] | None = Field(
        None, min_length=1, max_length=256, description="outputs kept per state (default: every pair's results)"
    )
    penetrating_start: Literal["approach", "refuse"] = "approach"


class OptimizeRequest(DocumentRequest):
    """A job: a design problem solved as one NLP (design variables and every load case's
    equilibrium), from one or more starts."""

    model_config = ConfigDict(
        json_schema_extra={
            "examples": [
                {"example": "grasper_shape"},
                {
                    "example": "grasper_shape",
                    "problem": {
                        "design": [
                            {"path": "/elements/link/length", "lower": 0.0508, "upper": 0.085},
                            {"path": "/elements/link/shape/coefficients/0", "lower": 0, "upper": 2},
                        ],
                        "objective": {"output": "reactions.tip.Fy"},
                        "constraints": [{"output": "elements.link.x_end_undeformed", "equals": 0.0508}],
                        "starts": 2,
                    },
                },
            ]
        }
    )

    problem: dict[str, Any] | None = Field(
        None,
        description="design problem: design [{path, lower, upper, scale}], objective {output, case, sense}, "
        "constraints [{output, case, lower, upper | equals}], cases {name: {overrides}}, starts, "
        "seed, max_iterations, tolerance (default: the document's optimize section)",
    )


# --- responses ------------------------------------------------------------------------------
class JobLinks(BaseModel):
    self: str
    result: str


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
