"""The sweep job's request: the numeric fields varied, the grid, the load path, the stop an
output sets, the outputs kept and the analysis of every point (service.jobs.sweep runs it)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from flexmech.models.documents.fields import MAX_POINTER_CHARS, OutputName, Pointer
from flexmech.service.jobs.base import JobOptions, StoredJob


class SweepParameter(BaseModel):
    """A numeric field's values: listed, or start to stop in equal steps (stop left out when the
    sweep has `until`: the value found is the stop)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    path: str = Field(pattern=r"^/", max_length=MAX_POINTER_CHARS, description="JSON pointer of a numeric field")
    values: list[float] | None = Field(None, min_length=1, description="document units")
    start: float | None = Field(None, description="document units")
    stop: float | None = Field(None, description="document units (with `until`: found)")
    steps: int | None = Field(None, ge=1, description="equal steps: steps + 1 values")

    @model_validator(mode="after")
    def _values_or_range(self) -> SweepParameter:
        ranged = (self.start, self.steps)
        if self.values is not None and any(v is not None for v in (*ranged, self.stop)):
            raise ValueError("give values, or start, stop and steps, not both")
        if self.values is None and any(v is None for v in ranged):
            raise ValueError("give values, or start, stop and steps")
        return self


class SweepUntil(BaseModel):
    """Sweep until an output reaches a value: the value of the (one, ranged) parameter at which
    it does is found first (as the equilibrium's target), and is the sweep's stop."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    output: OutputName = Field(description="the output", examples=["end_effector.x"])
    equals: float = Field(description="its value, in its document unit")


class SweepOptions(JobOptions):
    parameters: list[SweepParameter] = Field(
        min_length=1, max_length=8, json_schema_extra={"document_default": "/sweep"}
    )
    grid: Literal["cartesian", "zip"] = "cartesian"
    continuation: Pointer | None = Field(
        None,
        description="path of the swept parameter that is a load path: solved in order, each point from the previous one",
        json_schema_extra={"document_default": "/sweep/path"},
    )
    until: SweepUntil | None = Field(
        None,
        description="stop where an output reaches a value (one ranged parameter)",
        json_schema_extra={"document_default": "/sweep/until"},
    )
    outputs: list[OutputName] | None = Field(None, min_length=1, description="outputs to keep (default: all)")
    analysis: str = Field(
        "equilibrium",
        min_length=1,
        max_length=64,
        pattern=r"^[a-z_]+$",
        description="the analysis of every point (a sweepable one the schema lists)",
    )


class SweepSpec(StoredJob, SweepOptions):
    """A stored sweep job."""

    model_config = ConfigDict(extra="ignore")


# Requests worth showing (schemathesis sends every example): grids that once broke the service
# are answered 422 now.
SWEEP_EXAMPLES = [
    {
        "example": "gripper",
        "continuation": "/loads/actuation/force/1",
        "outputs": ["end_effector.x"],
        "parameters": [{"path": "/loads/actuation/force/1", "start": -60, "stop": 60, "steps": 20}],
    },
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
