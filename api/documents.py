"""A request's mechanism document: given inline, or named from the examples."""

from __future__ import annotations

from flexmech.api.errors import ApiError
from flexmech.api.schemas import DocumentRequest
from flexmech.api.state import Services
from flexmech.models.documents.text_bounds import check_text_bounds


def request_document(request: DocumentRequest, services: Services) -> dict:
    """The document of the request; an inline one's texts are checked against their bounds here,
    on the request's thread (a too-long name or description is a 422 before any worker sees it)."""
    if request.document is not None:
        check_text_bounds(request.document, "/document")
        return request.document
    example = services.examples.get(request.example)
    if example is None:
        known = ", ".join(services.examples.names()) or "none"
        raise ApiError(
            422, "invalid_input", f"/example: unknown example '{request.example}' (examples: {known})", "/example"
        )
    return example.document
