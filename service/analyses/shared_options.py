"""Option fields more than one analysis takes: a target, and the sensitivities asked for."""

from __future__ import annotations

from pydantic import Field

from service.analyses.base import AnalysisOptions


class Target(AnalysisOptions):
    """Find the value of numeric field `path` at which `output` equals `equals`."""

    path: str = Field(
        pattern=r"^/",
        max_length=256,
        description="JSON pointer of the numeric field solved for",
        examples=["/loads/actuation/force/1"],
        json_schema_extra={"document_default": "/sweep/path"},
    )
    output: str = Field(max_length=128, description="the output that reaches the value", examples=["end_effector.x"])
    equals: float = Field(description="the output's value, in its document unit")


class Sensitivities(AnalysisOptions):
    """Exact derivatives of outputs with respect to numeric fields at the solution (with a
    target: the target's field follows, and may be named among the outputs)."""

    parameters: list[str] = Field(
        min_length=1, max_length=64, description="JSON pointers of numeric fields", examples=[["/sections/flexure/h"]]
    )
    outputs: list[str] = Field(min_length=1, max_length=256, description="output names", examples=[["end_effector.x"]])
