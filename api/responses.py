"""The documented error responses of the routes (the shape is api.schemas.ErrorResponse)."""

from __future__ import annotations

from flexmech.api.schemas import ErrorResponse

_TEXT = {
    400: "Malformed JSON",
    401: "Missing or unknown API key (when the server has keys)",
    404: "No such job or example (jobs of other keys are not found either)",
    409: "The job is not in a state for it (cancelling a finished job; the archive of a job not succeeded)",
    413: "Request body over the size limit",
    422: "The request or its mechanism cannot be used; `pointer` names the field",
    429: "A quota of the key is full (`quota`, `used`, `limit`; `free` says how to free it): a new job is refused",
}


def errors(*statuses: int) -> dict:
    return {s: {"model": ErrorResponse, "description": _TEXT[s]} for s in statuses}


ERRORS = errors(400, 401, 413, 422)
JOB_ERRORS = errors(400, 401, 413, 422, 429)  # creating a job: quotas too
