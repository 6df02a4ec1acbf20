"""Request schemas of the workbench's helpers: a mechanism's drawing, and document text
(JSON or YAML) read into a document. Only pydantic here (the client imports it light)."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from flexmech.api.schemas import MAX_POINTER_CHARS, DocumentRequest, Name

MAX_DOCUMENT_TEXT = 2_000_000  # characters; the request body limit applies as well


class DrawnPath(BaseModel):
    """A numeric field taking its values in order (a load path): one drawn state per value."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    path: str = Field(pattern=r"^/", max_length=MAX_POINTER_CHARS, description="JSON pointer of a numeric field")
    values: list[float] = Field(min_length=1, max_length=400, description="document units, in path order")


class DrawingRequest(DocumentRequest):
    """The mechanism drawn to scale (document units): undeformed; or also deformed at the
    equilibrium under its loads (the overrides applied); or along a load path, a state per
    value, each solved from the one before."""

    state: Literal["undeformed", "equilibrium", "path"] = Field(
        "undeformed",
        description="equilibrium: also the deformed centre lines and every body's pose; "
        "path: `frames`, one such state per value of `path`",
    )
    path: DrawnPath | None = Field(None, description="state path: the field and its values")

    @model_validator(mode="after")
    def _path_given(self):
        if (self.state == "path") != (self.path is not None):
            raise ValueError("give path with state 'path' (and only then)")
        return self


class FabricationRequest(DocumentRequest):
    """The fabricated outlines of every body and flexure (service.drawings.fabrication) as a DXF
    (true arcs) or GDSII file (polygons within the chord error), in the document's length unit."""

    format: Literal["dxf", "gds"] = Field("dxf", description="dxf (for the shop) or gds (for a mask)")
    deformed: bool = Field(False, description="also the centre lines at the equilibrium under the document's loads")
    chord_error: float = Field(
        1e-4, gt=0, le=1, description="the farthest a polygon may leave a true arc (GDS, round corners), length unit"
    )


class DocumentText(BaseModel):
    """A document as text, read as JSON or YAML ("auto": JSON when it starts with '{')."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)  # as api.schemas' requests

    text: str = Field(max_length=MAX_DOCUMENT_TEXT)
    format: Literal["auto", "json", "yaml"] = "auto"


class DocumentUpgrade(BaseModel):
    """A document of an older shape (an `impacts` section), to be converted to today's."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    document: dict[Name, Any]
