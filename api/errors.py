"""Every error the API returns, mapped to a status code here and nowhere else.

Shape (api.schemas.ErrorResponse):
    {"error": {"status": 422, "code": "invalid_input", "message": "...", "pointer": "/document/..."}}

A 422 with problems in more than one field lists them all in "problems", the one the message
and pointer name first: [{"pointer": "/document/...", "message": "..."}, ...].

    400 malformed_json     the body is not JSON
    401 unauthorized       X-API-Key missing or not one of FLEXMECH_API_KEYS
    404 not_found          no such route, example or job (another key's job included)
    405 method_not_allowed
    413 body_too_large     the body exceeds FLEXMECH_MAX_REQUEST_BYTES
    422 invalid_request    the body does not fit the schema (pointer: the field)
    422 invalid_input      the mechanism or the analysis cannot be modelled (pointer: the field)
    422 duplicate_key      a key given twice in one object of the body (the message names it)
    408 request_timeout    the body did not arrive within FLEXMECH_REQUEST_READ_TIMEOUT
    409 conflict           e.g. cancelling a job that has finished
    429 quota_exceeded     a new job would pass one of the key's quotas (service.jobs.quotas): the
                           error's "quota" says which, with "used", "limit" and how to "free" it
    503 store_unavailable  the job store is locked or its disk full (Retry-After); nothing is lost
    500 internal_error     a bug: logged with its traceback, never shown to the caller
"""

from __future__ import annotations

import difflib
import logging
import re
import typing

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel
from sqlalchemy.exc import SQLAlchemyError
from starlette.exceptions import HTTPException as StarletteHTTPException

from flexmech.api import job_schemas, schemas
from flexmech.models import MechanismError
from flexmech.models.documents.text_bounds import too_long
from flexmech.models.errors import pointer_of
from flexmech.service.analyses import ANALYSES
from flexmech.service.jobs.kinds import job_kinds
from flexmech.service.jobs.quotas import QuotaExceeded

log = logging.getLogger("flexmech.api")


class ApiError(Exception):
    def __init__(self, status: int, code: str, message: str, pointer: str | None = None):
        self.status = status
        self.code = code
        self.message = message
        self.pointer = pointer
        super().__init__(message)

    def __reduce__(self):
        return (ApiError, (self.status, self.code, self.message, self.pointer))


def not_found(what: str) -> ApiError:
    return ApiError(404, "not_found", what)


# An error names what the caller sent (a name, a path, a value) but never echoes a long one
# whole: a run of more than LONG_WORD characters without a blank is cut to its start, and
# the whole message to MAX_MESSAGE characters.
LONG_WORD, KEPT, MAX_MESSAGE = 120, 100, 2000
_LONG_WORD = re.compile(rf"\S{{{LONG_WORD + 1},}}")


def excerpt(text: str) -> str:
    text = _LONG_WORD.sub(lambda m: f"{m.group()[:KEPT]}...({len(m.group())} characters)", text)
    return text if len(text) <= MAX_MESSAGE else text[:MAX_MESSAGE] + f"...({len(text)} characters)"


def error_response(
    status: int,
    code: str,
    message: str,
    pointer: str | None = None,
    headers: dict | None = None,
    problems: list[tuple[str, str]] | None = None,
    details: dict | None = None,
) -> JSONResponse:
    """The error's body; `problems` (pointer, message) of every field, kept when more than one;
    `details`, further fields of the error (a quota's use and limit)."""
    pointer = None if pointer is None else excerpt(pointer)
    error: dict = {"status": status, "code": code, "message": excerpt(message), "pointer": pointer, **(details or {})}
    if problems and len(problems) > 1:
        error["problems"] = [{"pointer": excerpt(where), "message": excerpt(what)} for where, what in problems]
    return JSONResponse({"error": error}, status_code=status, headers=headers)


_UNION_MEMBERS = ("float", "str", "int", "bool", "constrained-str")


def _validation_pointer(loc: tuple) -> str:
    parts = list(loc)
    if parts and parts[0] in ("body", "query", "path", "header"):
        parts = parts[1:]
    # pydantic names union members and validator types in locations; they are not fields
    parts = [
        p for p in parts if not (isinstance(p, str) and (p.startswith("function-") or "[" in p or p in _UNION_MEMBERS))
    ]
    return pointer_of(tuple(parts))


# Top-level fields of a mechanism document: a body made of them is a document sent unwrapped.
_DOCUMENT_FIELDS = {"schema_version", "units", "materials", "sections", "bodies", "elements", "loads", "outputs"}


def _unwrapped_document(body) -> bool:
    return (
        isinstance(body, dict)
        and "document" not in body
        and "example" not in body
        and len(_DOCUMENT_FIELDS & set(body)) >= 2
    )


def _error_pointer(error: dict) -> str:
    if error.get("type", "").startswith("union_tag_"):  # the solve request's tag: its analysis
        return "/analysis"
    loc = tuple(error.get("loc", ()))
    if loc[-1:] == ("[key]",):  # a key too long: its object's error, the key not echoed
        loc = loc[:-2]
    return _validation_pointer(loc)


def _fields_of(models: list[type[BaseModel]]) -> dict[str, type[BaseModel]]:
    """Every field name of the models and the models nested in them, with one model naming it."""
    names: dict[str, type[BaseModel]] = {}
    stack, seen = list(models), set()
    while stack:
        model = stack.pop()
        if model in seen:
            continue
        seen.add(model)
        for name, info in model.model_fields.items():
            names.setdefault(info.alias or name, model)
            stack += [
                t
                for t in getattr(info.annotation, "__args__", (info.annotation,))
                if isinstance(t, type) and issubclass(t, BaseModel)
            ]
    return names


def _request_field_names() -> tuple[str, ...]:
    models = [
        m
        for module in (schemas, job_schemas)
        for m in vars(module).values()
        if isinstance(m, type) and issubclass(m, BaseModel)
    ]
    kinds = [kind.Options for kind in job_kinds().values()]
    return tuple(sorted(_fields_of(models + [a.Options for a in ANALYSES] + kinds)))


def _home_within(key: str, analysis: str) -> str:
    """' (it belongs under trace: /trace/path)' when a group of the analysis' own options
    has the field, as a misplaced top-level field usually does."""
    options = next((a.Options for a in ANALYSES if a.name == analysis), None)
    for name, field in (options.model_fields if options else {}).items():
        for inner in typing.get_args(field.annotation) or (field.annotation,):
            if isinstance(inner, type) and issubclass(inner, BaseModel) and key in inner.model_fields:
                return f" (it belongs under {name}: /{name}/{key})"
    return ""


def _taken_by(key: str, analysis: str | None) -> str:
    """' (the trace analysis takes it)' when another analysis' options have the field."""
    takers = [a.name for a in ANALYSES if a.name != analysis and key in a.Options.model_fields]
    return f" (the {' and '.join(takers)} analysis takes it)" if takers else ""


def _message(first: dict) -> str:
    message = first.get("msg", "invalid")
    kind = first.get("type")
    if kind == "missing":
        return "required field is missing"
    if kind == "string_too_long":  # never the text itself: its length
        key = tuple(first.get("loc", ()))[-1:] == ("[key]",)
        return too_long(first["ctx"]["max_length"], len(first.get("input") or ""), key)
    if kind == "union_tag_invalid":  # the solve request's tag (api.analysis_requests)
        return f"unknown analysis '{first['ctx']['tag'].strip('[]')}' (analyses: {', '.join(ANALYSES.names())})"
    if kind == "union_tag_not_found":
        return f"expected the name of an analysis ({', '.join(ANALYSES.names())})"
    if kind == "extra_forbidden":
        loc = first.get("loc", ("",))
        key = str(loc[-1])
        analysis = next((p.strip("[]") for p in loc if isinstance(p, str) and p.startswith("[")), None)
        if analysis is not None and len(loc) <= 3:  # a top-level field of a solve request
            taken = _home_within(key, analysis) or _taken_by(key, analysis)
            if taken:
                return f"unknown field '{key}' for the {analysis} analysis{taken}"
        others = [
            name for name in _request_field_names() if name != key
        ]  # a field of that name elsewhere is no suggestion
        close = difflib.get_close_matches(key, others, n=1, cutoff=0.75)
        return f"unknown field '{key}'" + (f" (did you mean '{close[0]}'?)" if close else "")
    return message[len("Value error, ") :] if message.startswith("Value error, ") else message


def _on_validation_error(_request: Request, exc: RequestValidationError) -> JSONResponse:
    errors = exc.errors()
    for e in errors:
        if e.get("type") == "json_invalid":
            detail = e.get("ctx", {}).get("error", "")
            return error_response(400, "malformed_json", f"the body is not valid JSON: {detail}".rstrip(": "))
    if _unwrapped_document(getattr(exc, "body", None)):
        return error_response(
            422,
            "invalid_request",
            "body: this is a mechanism document itself: send it as "
            '{"document": <the document>} (or name one of GET /v1/examples as {"example": "<name>"})',
            "",
        )
    first = next((e for e in errors if e.get("type") == "extra_forbidden"), None)
    # a text too long is told before its union's other members' complaints (a quantity's "not a float")
    first = first or next((e for e in errors if e.get("type") == "string_too_long"), errors[0])
    pointer = _error_pointer(first)
    message = _message(first)
    problems = {pointer: message}
    for error in errors:
        problems.setdefault(_error_pointer(error), _message(error))
    others = len(problems) - 1
    if others:
        message += f" (and {others} more field{'s' if others > 1 else ''} with problems)"
    where = pointer or "body"
    return error_response(422, "invalid_request", f"{where}: {message}", pointer, problems=list(problems.items()))


def _on_mechanism_error(_request: Request, exc: MechanismError) -> JSONResponse:
    return error_response(422, "invalid_input", str(exc), exc.pointer, problems=list(exc.problems))


def _on_api_error(_request: Request, exc: ApiError) -> JSONResponse:
    headers = {"WWW-Authenticate": "ApiKey"} if exc.status == 401 else None
    return error_response(exc.status, exc.code, exc.message, exc.pointer, headers)


_HTTP_CODES = {404: "not_found", 405: "method_not_allowed", 400: "bad_request", 413: "body_too_large"}


def _on_quota_exceeded(_request: Request, exc: QuotaExceeded) -> JSONResponse:
    headers = {"Retry-After": "10"} if exc.quota == "running" else None  # the others wait for a DELETE
    return error_response(429, "quota_exceeded", str(exc), headers=headers, details=exc.details())


def _on_http_error(_request: Request, exc: StarletteHTTPException) -> JSONResponse:
    code = _HTTP_CODES.get(exc.status_code, "http_error")
    message = exc.detail if isinstance(exc.detail, str) else "error"
    return error_response(exc.status_code, code, message, headers=getattr(exc, "headers", None))


def _on_store_error(request: Request, exc: SQLAlchemyError) -> JSONResponse:
    log.error("job store unavailable on %s %s: %s", request.method, request.url.path, str(exc).splitlines()[0][:300])
    return error_response(
        503,
        "store_unavailable",
        "the job store cannot be read or written just now (the "
        "database is locked or its disk is full): try again shortly",
        headers={"Retry-After": "5"},
    )


def _on_unexpected(request: Request, exc: Exception) -> JSONResponse:
    log.exception("unhandled error on %s %s", request.method, request.url.path)
    return error_response(500, "internal_error", "internal error; it has been logged")


def install_error_handlers(app: FastAPI) -> None:
    app.add_exception_handler(RequestValidationError, _on_validation_error)
    app.add_exception_handler(MechanismError, _on_mechanism_error)
    app.add_exception_handler(ApiError, _on_api_error)
    app.add_exception_handler(QuotaExceeded, _on_quota_exceeded)
    app.add_exception_handler(StarletteHTTPException, _on_http_error)
    app.add_exception_handler(SQLAlchemyError, _on_store_error)
    app.add_exception_handler(Exception, _on_unexpected)
