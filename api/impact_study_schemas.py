"""The request of an impact study job (POST /v1/impact-studies)."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field

from api.schemas import DocumentRequest


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class StudyField(_Strict):
    path: str = Field(pattern=r"^/", max_length=256, description="a number of the document, by JSON pointer")
    step: float = Field(description="it moves by +step and by -step, in the document's units")


class ImpactStudy(_Strict):
    fields: list[StudyField] = Field(min_length=1, max_length=64)
    tolerance: float = Field(
        0.05,
        gt=0,
        lt=1,
        description="a run departs from the nominal one when a quantity "
        "differs by more than this fraction of its nominal range",
    )


class ImpactStudyRequest(DocumentRequest):
    """A job: seed 004's parametric study of an impact simulation, one field at a time."""

    model_config = ConfigDict(
        json_schema_extra={
            "examples": [
                {
                    "example": "csfh",
                    "simulate": {"until": 0.3},
                    "study": {
                        "fields": [
                            {"path": "/contacts/sites/pin/radius", "step": 0.001},
                            {"path": "/bodies/hinge/mass", "step": 0.1},
                        ]
                    },
                },
            ]
        }
    )

    simulate: dict[str, Any] | None = Field(None, description="fields of the document's `simulate` section over it")
    study: ImpactStudy
