"""Request and response schemas of the HTTP API, shared by the server and the Python client.

Only pydantic here: the client imports this module without CasADi or FastAPI. Numbers in requests and responses are
in the units the mechanism document declares (its `units`), and each response says which unit goes with which number."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, StringConstraints, model_validator

# The models of a curved beam: models.MODELS, which a test pins this list to (the client does not import the core).
Model = Literal["linear", "partial_nonlinear", "exact", "conservative"]
PointStatus = Literal["converged", "not_converged", "singular", "time_limit", "infeasible"]

# The document's bounds on text (models.documents.fields, which a test pins these to; the client
# does not import the core): a request's own text is bounded as the document's is.
MAX_NAME_CHARS = 200  # a name, and a key of the document (its fields, a named collection's objects)
MAX_DESCRIPTION_CHARS = 20_000  # the document's description
MAX_POINTER_CHARS = 256  # a JSON pointer to a field of the document
MAX_QUANTITY_CHARS = 100  # a number with its unit, "25 um"
Name = Annotated[str, StringConstraints(max_length=MAX_NAME_CHARS)]
Pointer = Annotated[str, StringConstraints(max_length=MAX_POINTER_CHARS)]
Quantity = Annotated[str, StringConstraints(max_length=MAX_QUANTITY_CHARS)]


class RequestModel(BaseModel):
    """A request's object: unknown fields are errors, numbers finite."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class ResponseModel(BaseModel):
    """A response's object: a newer server's further fields are kept, not refused."""

    model_config = ConfigDict(extra="allow")


# --- requests -------------------------------------------------------------------------------
class NewtonOptionsIn(RequestModel):
    """Newton's method. Tolerances are on nondimensional infinity norms."""

    tol_residual: float | None = Field(None, gt=0, le=1e-2)
    tol_step: float | None = Field(None, gt=0, le=1e-2)
    max_iterations: int | None = Field(None, ge=1, le=1000)
    line_search: bool | None = None
    jacobian: Literal["full", "first_term", "frozen"] | None = None
    time_limit: float | None = Field(None, gt=0, description="seconds; the server's limit caps it")

    def given(self) -> dict[str, Any]:
        return self.model_dump(exclude_none=True)


class DocumentRequest(RequestModel):
    document: dict[Name, Any] | None = Field(
        None,
        description="A mechanism document (JSON object). Give this or `example`. Its texts are bounded: its name "
        f"at most {MAX_NAME_CHARS} characters, its description {MAX_DESCRIPTION_CHARS}, every other text as the "
        "document's schema says (a text over its bound is a 422 naming the field)",
    )
    example: str | None = Field(
        None,
        min_length=1,
        max_length=64,
        pattern=r"^[A-Za-z0-9_.-]+$",
        description="The name of an example document (GET /v1/examples)",
    )
    model: Model | None = Field(None, description="Model of every curved beam (default: as in the document)")
    overrides: dict[Pointer, float | Quantity] = Field(
        default_factory=dict,
        description="Numeric fields replaced, by JSON pointer into the document",
        examples=[{"/loads/actuation/force/1": 50}],
    )
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


# --- responses ------------------------------------------------------------------------------
class Problem(BaseModel):
    pointer: str = Field(description="JSON pointer of the field in the request body")
    message: str = Field(description="what is wrong with it")


class ErrorBody(BaseModel):
    status: int = Field(description="the HTTP status code")
    code: str = Field(description="stable machine-readable code, e.g. invalid_input, not_found")
    message: str = Field(description="what is wrong, naming the field")
    pointer: str | None = Field(None, description="JSON pointer of the offending field in the request body")
    problems: list[Problem] | None = Field(
        None, description="every field with a problem, when more than one has (the one `pointer` names first)"
    )
    quota: str | None = Field(None, description="429: the quota that is full (jobs, bytes or running)")
    used: int | None = Field(None, description="429: what the key uses of it")
    limit: int | None = Field(None, description="429: the quota's limit")
    free: str | None = Field(None, description="429: how to free it")


class ErrorResponse(BaseModel):
    """Every error of the API has this shape."""

    error: ErrorBody


class StiffnessOut(ResponseModel):
    coordinates: list[str]
    row_units: list[str]
    column_units: list[str]
    K: list[list[float | None]]
    terms: dict[str, list[list[float | None]]]
    symmetric: bool


class WrenchOut(ResponseModel):
    Fx: float | None
    Fy: float | None
    M: float | None


class TargetOut(ResponseModel):
    path: str
    value: float | None = Field(description="the field's value that reaches the target")
    unit: str
    status: PointStatus


class ContactPairOut(ResponseModel):
    """One contact pair at a state (document units): the force on the site and its parts."""

    state: Literal["open", "frictionless", "slipping", "sticking"]
    force: list[float | None] = Field(description="on the site, global axes")
    normal_force: float | None
    friction_force: float | None = Field(description="along the tangent (the normal turned by +90 deg)")
    normal: list[float | None] | None = Field(description="unit, out of the object (None when open)")
    point: list[float | None] | None = Field(description="the contact point (None when open)")
    site_parameter: float | None = Field(description="arc length along the jaw or the link (None when open)")
    gap: float | None


class AnalysisReport(ResponseModel):
    """Any analysis' report: what every report holds; its own fields are attributes too (the
    server's GET /v1/analyses has each analysis' result schema)."""

    analysis: str
    name: str
    status: str
    message: str = ""
    warnings: list[str] = Field(default_factory=list)


class SolveResponse(ResponseModel):
    analysis: str
    name: str
    status: PointStatus | Literal["finished"] = Field(description='"finished": a simulation reached its end')
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
        default_factory=dict, description="per output its value (a simulation: its value at every kept time)"
    )
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


class ExampleSummary(BaseModel):
    name: str
    title: str
    description: str = ""


class HealthResponse(BaseModel):
    status: Literal["ok", "degraded"] = Field(
        description="ok; degraded while the kernel builder is down (the server starts it again, with backoff: "
        "requests are answered, with kernels interpreted, and builds wait in the queue)"
    )
    version: str
    database: str = Field(description="sqlite or postgresql")
    executor: str
    active_jobs: int
    builder: dict[str, int | bool | str | None] | None = Field(
        None,
        description="its kernel build queue (none when kernels are not built here): pid, running, queued (requests "
        "waiting), restarts (times the server started it again), and while it is down, reason",
    )
