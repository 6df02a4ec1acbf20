"""Option fields more than one analysis takes: a target, and the sensitivities asked for."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BeforeValidator, Field, StringConstraints

from flexmech.models.documents.fields import MAX_OUTPUT_CHARS, MAX_POINTER_CHARS, OutputName
from flexmech.service.analyses.base import AnalysisOptions

MAX_NAMES = 1000  # distinct outputs or fields one request may watch


def _distinct(value: Any) -> Any:
    """A name given twice is watched once: duplicates are dropped, first places kept. A report
    keys its values by name, so 500 copies of one output once computed 500 columns (2.5 GB in a
    worker) to answer one."""
    if isinstance(value, list) and all(isinstance(item, str) for item in value):
        return list(dict.fromkeys(value))
    return value


NameOrPointer = Annotated[str, StringConstraints(max_length=max(MAX_OUTPUT_CHARS, MAX_POINTER_CHARS))]
Names = Annotated[list[NameOrPointer], BeforeValidator(_distinct)]
"""A list of output names or JSON pointers, each kept once (its limits, checked after, count
distinct names)."""


class Target(AnalysisOptions):
    """Find the value of numeric field `path` at which `output` equals `equals`."""

    path: str = Field(
        pattern=r"^/",
        max_length=MAX_POINTER_CHARS,
        description="JSON pointer of the numeric field solved for",
        examples=["/loads/actuation/force/1"],
        json_schema_extra={"document_default": "/sweep/path"},
    )
    output: OutputName = Field(description="the output that reaches the value", examples=["end_effector.x"])
    equals: float = Field(description="the output's value, in its document unit")


class Sensitivities(AnalysisOptions):
    """Exact derivatives of outputs with respect to numeric fields at the solution (with a
    target: the target's field follows, and may be named among the outputs)."""

    parameters: Names = Field(
        min_length=1, max_length=64, description="JSON pointers of numeric fields", examples=[["/sections/flexure/h"]]
    )
    outputs: Names = Field(min_length=1, max_length=256, description="output names", examples=[["end_effector.x"]])
