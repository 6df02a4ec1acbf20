"""What both clients (api.client) share: the API's errors as exceptions, reading answers, and
the body of a request. Only httpx and pydantic: the light client install has nothing else."""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from typing import Any, TypeVar

import httpx
from pydantic import BaseModel, TypeAdapter

from flexmech.api.job_schemas import JobStatusResponse

T = TypeVar("T")
Progress = Callable[[JobStatusResponse], None]
DEFAULT_URL = "http://127.0.0.1:8000"


class FlexmechError(Exception):
    """An error answer of the API: its status, code, message, the request field's pointer,
    and the error's further fields (`details`: a 429's quota, used, limit and free)."""

    def __init__(self, status: int, code: str, message: str, pointer: str | None = None, details: dict | None = None):
        self.status = status
        self.code = code
        self.message = message
        self.pointer = pointer
        self.details = details or {}
        super().__init__(f"{status} {code}: {message}")

    def __reduce__(self):  # pickled with its fields (a client used from worker processes)
        return (FlexmechError, (self.status, self.code, self.message, self.pointer, self.details))


class JobTimeout(TimeoutError):
    """wait() gave up before the job finished; the job goes on on the server."""

    def __init__(self, status: JobStatusResponse):
        self.status = status
        super().__init__(
            f"job {status.id} still {status.status} after waiting "
            f"({status.progress.done} of {status.progress.total} points)"
        )

    def __reduce__(self):
        return (JobTimeout, (self.status,))


def error_of(response: httpx.Response) -> FlexmechError:
    try:
        body = response.json()["error"]
        known = {"status", "code", "message", "pointer", "problems"}
        details = {k: v for k, v in body.items() if k not in known}
        return FlexmechError(body["status"], body["code"], body["message"], body.get("pointer"), details)
    except (ValueError, KeyError, TypeError):
        return FlexmechError(response.status_code, "http_error", response.text[:500] or response.reason_phrase)


def parse(response: httpx.Response, model: type[T] | TypeAdapter) -> T:
    if response.status_code >= 400:
        raise error_of(response)
    data = response.json()
    if isinstance(model, TypeAdapter):
        return model.validate_python(data)
    if model in (dict, list):
        return data
    return model.model_validate(data)


def bytes_of(response: httpx.Response) -> bytes:
    if response.status_code >= 400:
        raise error_of(response)
    return response.content


def request_body(model: type[BaseModel], request: BaseModel | None, fields: dict[str, Any]) -> dict:
    if request is None:
        request = model(**fields)
    elif fields:
        raise TypeError("give a request object or keyword fields, not both")
    return request.model_dump(mode="json", exclude_none=True)


def finished(status: JobStatusResponse, deadline: float | None, progress: Progress | None) -> bool:
    """One step of wait(): report progress; True once the job has finished; JobTimeout past
    the deadline."""
    if progress is not None:
        progress(status)
    if status.finished:
        return True
    if deadline is not None and time.monotonic() >= deadline:
        raise JobTimeout(status)
    return False


def page(offset: int, limit: int | None) -> dict[str, int]:
    return {"offset": offset} | ({"limit": limit} if limit is not None else {})


def where(base_url: str | None, api_key: str | None) -> tuple[str, str | None]:
    """The server and key: as given, else $FLEXMECH_URL and $FLEXMECH_API_KEY, else the local server."""
    return base_url or os.environ.get("FLEXMECH_URL") or DEFAULT_URL, api_key or os.environ.get("FLEXMECH_API_KEY")


def headers(api_key: str | None) -> dict[str, str]:
    return {"X-API-Key": api_key} if api_key else {}
