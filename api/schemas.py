"""Request and response schemas of the HTTP API, shared by the server and the Python client.

Only pydantic here: the client imports this module without CasADi or FastAPI. Numbers in requests and responses are
in the units the mechanism document declares (its `units`), and each response says which unit goes with which number."""

from __future__ import annotations

from datetime import datetime
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

# The models of a curved beam: models.MODELS, which a test pins this list to (the client does not import the core).
Model = Literal["linear", "partial_nonlinear", "exact", "conservative"]
JobStatusName = Literal["queued", "running", "succeeded", "failed", "cancelled"]
PointStatus = Literal["converged", "not_converged", "singular", "time_limit", "infeasible"]


class _Request(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class _Response(BaseModel):
    model_config = ConfigDict(extra="allow")


# --- requests -------------------------------------------------------------------------------
class NewtonOptionsIn(_Request):
    """Newton's method. Tolerances are on nondimensional infinity norms."""

    tol_residual: float | None = Field(None, gt=0, le=1e-2)
    tol_step: float | None = Field(None, gt=0, le=1e-2)
    max_iterations: int | None = Field(None, ge=1, le=1000)
    line_search: bool | None = None
    jacobian: Literal["full", "first_term", "frozen"] | None = None
    time_limit: float | None = Field(None, gt=0, description="seconds; the server's limit caps it")

    def given(self) -> dict[str, Any]:
        return self.model_dump(exclude_none=True)


class DocumentRequest(_Request):
    document: dict[str, Any] | None = Field(
        None, description="A mechanism document (JSON object). Give this or `example`.")
    example: str | None = Field(None, min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.-]+$",
                                description="The name of an example document (GET /v1/examples)")
    model: Model | None = Field(None, description="Model of every curved beam (default: as in the document)")
    overrides: dict[str, float | str] = Field(
        default_factory=dict, description="Numeric fields replaced, by JSON pointer into the document",
        examples=[{"/loads/actuation/force/1": 50}])
    options: NewtonOptionsIn | None = None

    @model_validator(mode="after")
    def _one_source(self):
        if (self.document is None) == (self.example is None):
            raise ValueError("give exactly one of document and example")
        return self


class SolveRequest(DocumentRequest):
    """One analysis of one mechanism, as the client sends it: the analysis' own options are
    further fields, which the server checks against that analysis' options model (GET
    /v1/analyses lists them; /openapi.json has the request of each analysis)."""

    model_config = ConfigDict(extra="allow")

    analysis: str = Field("equilibrium", min_length=1, max_length=64, description="an analysis the server offers")


class SweepParameter(_Request):
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


class SweepUntil(_Request):
    """Sweep until an output reaches a value: the value of the (one, ranged) parameter at which
    it does is found first (as the equilibrium's target), and is the sweep's stop."""

    output: str = Field(max_length=128, description="the output", examples=["end_effector.x"])
    equals: float = Field(description="its value, in its document unit")


class SweepRequest(DocumentRequest):
    """A job: numeric fields varied over a grid, each point an equilibrium (or a sweepable analysis)."""

    model_config = ConfigDict(json_schema_extra={"examples": [
        {"example": "gripper", "continuation": "/loads/actuation/force/1", "outputs": ["end_effector.x"],
         "parameters": [{"path": "/loads/actuation/force/1", "start": -60, "stop": 60, "steps": 20}]},
        # grids that once broke the service, answered 422 now (schemathesis sends every example)
        {"example": "gripper", "parameters": [{"path": "/loads/actuation/force/1", "start": 0, "stop": 1,
                                               "steps": 1_000_000_000}]},
        {"example": "gripper", "parameters": [{"path": "/loads/actuation/force/1", "start": 0, "stop": 1,
                                               "steps": 10**30}]},
        {"example": "gripper", "parameters": [{"path": p, "start": 0.1, "stop": 0.2, "steps": 65535}
                                              for p in ("/loads/actuation/force/0", "/loads/actuation/force/1",
                                                        "/sections/flexure/h", "/sections/flexure/b")]},
        {"example": "gripper", "parameters": [{"path": "/elements/a/radius", "values": [0.2, 0, -1]}]},
        {"example": "gripper", "parameters": [{"path": "/elements/a/arc_angle", "values": [400]}]},
    ]})

    parameters: list[SweepParameter] = Field(min_length=1, max_length=8, json_schema_extra={"document_default": "/sweep"})
    grid: Literal["cartesian", "zip"] = "cartesian"
    continuation: str | None = Field(
        None, description="path of the swept parameter that is a load path: solved in order, "
                          "each point from the previous one", json_schema_extra={"document_default": "/sweep/path"})
    until: SweepUntil | None = Field(None, description="stop where an output reaches a value (one ranged parameter)",
                                     json_schema_extra={"document_default": "/sweep/until"})
    outputs: list[str] | None = Field(None, min_length=1, description="outputs to keep (default: all)")
    analysis: str = Field("equilibrium", min_length=1, max_length=64, pattern=r"^[a-z_]+$",
                          description="the analysis of every point (a sweepable one the schema lists)")


class ContactPathRequest(DocumentRequest):
    """A job: a quasi-static contact path (fields changing together, state after state, each
    from the one before); without `path`, the document's contacts.path."""

    model_config = ConfigDict(json_schema_extra={"examples": [
        {"example": "gripper_jaw_contact"},
        {"example": "gripper_jaw_contact", "outputs": ["contacts.insertion.force_x"],
         "path": [{"path": "/contacts/objects/fixture/centre/0", "start": 78, "stop": 50, "steps": 28}]},
        {"example": "gripper_jaw_contact", "path": [{"path": "/contacts/objects/fixture/centre/0", "start": 78,
                                                      "stop": 50, "steps": 10**12}]},
    ]})

    path: list[SweepParameter] | None = Field(None, min_length=1, max_length=8,
                                              description="fields that change together along the path",
                                              json_schema_extra={"document_default": "/contacts/path/parameters/0"})
    outputs: list[str] | None = Field(None, min_length=1, max_length=256,
                                      description="outputs kept per state (default: every pair's results)")
    penetrating_start: Literal["approach", "refuse"] = "approach"


class OptimizeRequest(DocumentRequest):
    """A job: a design problem solved as one NLP (design variables and every load case's
    equilibrium), from one or more starts."""

    model_config = ConfigDict(json_schema_extra={"examples": [
        {"example": "grasper_shape"},
        {"example": "grasper_shape", "problem": {
            "design": [{"path": "/elements/link/length", "lower": 0.0508, "upper": 0.085},
                       {"path": "/elements/link/shape/coefficients/0", "lower": 0, "upper": 2}],
            "objective": {"output": "reactions.tip.Fy"},
            "constraints": [{"output": "elements.link.x_end_undeformed", "equals": 0.0508}], "starts": 2}},
    ]})

    problem: dict[str, Any] | None = Field(
        None, description="design problem: design [{path, lower, upper, scale}], objective {output, case, sense}, "
                          "constraints [{output, case, lower, upper | equals}], cases {name: {overrides}}, starts, "
                          "seed, max_iterations, tolerance (default: the document's optimize section)")


# --- responses ------------------------------------------------------------------------------
class ErrorBody(BaseModel):
    status: int = Field(description="the HTTP status code")
    code: str = Field(description="stable machine-readable code, e.g. invalid_input, not_found")
    message: str = Field(description="what is wrong, naming the field")
    pointer: str | None = Field(None, description="JSON pointer of the offending field in the request body")


class ErrorResponse(BaseModel):
    """Every error of the API has this shape."""

    error: ErrorBody


class StiffnessOut(_Response):
    coordinates: list[str]
    row_units: list[str]
    column_units: list[str]
    K: list[list[float | None]]
    terms: dict[str, list[list[float | None]]]
    symmetric: bool


class WrenchOut(_Response):
    Fx: float | None
    Fy: float | None
    M: float | None


class TargetOut(_Response):
    path: str
    value: float | None = Field(description="the field's value that reaches the target")
    unit: str
    status: PointStatus


class ContactPairOut(_Response):
    """One contact pair at a state (document units): the force on the site and its parts."""

    state: Literal["open", "frictionless", "slipping", "sticking"]
    force: list[float | None] = Field(description="on the site, global axes")
    normal_force: float | None
    friction_force: float | None = Field(description="along the tangent (the normal turned by +90 deg)")
    normal: list[float | None] | None = Field(description="unit, out of the object (None when open)")
    point: list[float | None] | None = Field(description="the contact point (None when open)")
    site_parameter: float | None = Field(description="arc length along the jaw or the link (None when open)")
    gap: float | None


class AnalysisReport(_Response):
    """Any analysis' report: what every report holds; its own fields are attributes too (the
    server's GET /v1/analyses has each analysis' result schema)."""

    analysis: str
    name: str
    status: str
    message: str = ""
    warnings: list[str] = Field(default_factory=list)


class SolveResponse(_Response):
    analysis: str
    name: str
    status: PointStatus | Literal["finished"] = Field(description="\"finished\": a simulation reached its end")
    message: str = ""
    iterations: int = 0
    residual_norm: float | None = Field(None, description="the largest unbalanced force (residual_unit)")
    residual_unit: str | None = None
    residual_moment: float | None = Field(None, description="the largest unbalanced moment (residual_moment_unit)")
    residual_moment_unit: str | None = None
    solver_residual: float | None = Field(None, description="nondimensional norm of every row: Newton's test")
    seconds: float | None = None
    warnings: list[str] = Field(default_factory=list)
    displacements: dict[str, float | None] = Field(default_factory=dict)
    displacement_units: dict[str, str] = Field(default_factory=dict)
    outputs: dict[str, float | None | list[float | None]] = Field(
        default_factory=dict, description="per output its value (a simulation: its value at every kept time)")
    output_units: dict[str, str] = Field(default_factory=dict)
    history: list[float | None] = Field(default_factory=list)
    stiffness: StiffnessOut | None = None
    target: TargetOut | None = None
    sensitivities: dict[str, Any] | None = None
    wrenches: dict[str, WrenchOut] | None = None
    wrench_units: dict[str, str] | None = None
    pairs: dict[str, ContactPairOut] | None = Field(None, description="contact: every pair's state and forces")
    units: dict[str, str] | None = Field(None, description="contact: the units of the pairs' numbers")
    approach_steps: int | None = Field(None, description="contact: steps taken from a penetrating start")
    kkt_residual: float | None = Field(None, description="contact: the largest residual of its KKT system (force unit)")
    thesis_recovery: dict[str, Any] | None = Field(None, description="contact: the thesis' recovery, labelled")


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


class SweepPoint(_Response):
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
    until: dict[str, Any] | None = Field(None, description="with until: its output, value, and the parameter's "
                                                           "value found (path, value, unit)")
    points: list[SweepPoint]


class ContactStateOut(_Response):
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


class ExampleSummary(BaseModel):
    name: str
    title: str
    description: str = ""


class HealthResponse(BaseModel):
    status: Literal["ok"]
    version: str
    database: str = Field(description="sqlite or postgresql")
    executor: str
    active_jobs: int
    builder: dict[str, int | bool] | None = Field(None, description="its kernel build queue: pid, running, queued")
