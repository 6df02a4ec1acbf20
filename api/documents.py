"""A request's mechanism document: given inline, or named from the examples."""

from __future__ import annotations

from flexmech.api.errors import ApiError
from flexmech.api.schemas import DocumentRequest
from flexmech.api.state import Services


def request_document(request: DocumentRequest, services: Services) -> dict:
    if request.document is not None:
        return request.document
    example = services.examples.get(request.example)
    if example is None:
        known = ", ".join(services.examples.names()) or "none"
        raise ApiError(
            422, "invalid_input", f"/example: unknown example '{request.example}' (examples: {known})", "/example"
        )
    return example.document
