"""Request schemas of the workbench's helpers: a mechanism's drawing, and document text
(JSON or YAML) read into a document. Only pydantic here (the client imports it light)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from api.schemas import DocumentRequest

MAX_DOCUMENT_TEXT = 2_000_000  # characters; the request body limit applies as well


class DrawingRequest(DocumentRequest):
    """The mechanism drawn to scale (document units): undeformed, or also deformed at the
    equilibrium under its loads (the overrides applied)."""

    state: Literal["undeformed", "equilibrium"] = Field(
        "undeformed", description="equilibrium: also the deformed centre lines and every body's pose")


class DocumentText(BaseModel):
    """A document as text, read as JSON or YAML ("auto": JSON when it starts with '{')."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)  # as api.schemas' requests

    text: str = Field(max_length=MAX_DOCUMENT_TEXT)
    format: Literal["auto", "json", "yaml"] = "auto"
