"""The `trace` field of a solve request (the trace analysis). Its own module, as api.schemas is
at the size limit of a module; pydantic only (the client imports it)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field


class TraceIn(BaseModel):
    """Follow the equilibrium path of numeric field `path` from its value in the document until
    it passes `stop`, through limit points (pseudo-arc-length continuation)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)  # as api.schemas' requests

    path: str = Field(pattern=r"^/", max_length=256, examples=["/loads/P/force/1"])
    stop: float = Field(description="document units of the field")
    step: float = Field(gt=0, description="the first arc-length step, document units of the field")
    max_points: int = Field(400, ge=2, le=100_000, description="points of the path at most")
