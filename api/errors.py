"""Every error the API returns, mapped to a status code here and nowhere else.

Shape (api.schemas.ErrorResponse):
    {"error": {"status": 422, "code": "invalid_input", "message": "...", "pointer": "/document/..."}}

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
    503 store_unavailable  the job store is locked or its disk full (Retry-After); nothing is lost
    500 internal_error     a bug: logged with its traceback, never shown to the caller
"""

from __future__ import annotations

import difflib
import logging
import re
from functools import lru_cache

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel
from sqlalchemy.exc import SQLAlchemyError
from starlette.exceptions import HTTPException as StarletteHTTPException

from api import schemas
from models import MechanismError
from models.errors import pointer_of

log = logging.getLogger("flexmech.api")

class ApiError(Exception):
    def __init__(self, status: int, code: str, message: str, pointer: str | None = None):
        self.status = status
        self.code = code
        self.message = message
        self.pointer = pointer
        super().__init__(message)

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


def error_response(status: int, code: str, message: str, pointer: str | None = None,
                   headers: dict | None = None) -> JSONResponse:
    pointer = None if pointer is None else excerpt(pointer)
    body = {"error": {"status": status, "code": code, "message": excerpt(message), "pointer": pointer}}
    return JSONResponse(body, status_code=status, headers=headers)

def _validation_pointer(loc: tuple) -> str:
    parts = list(loc)
    if parts and parts[0] in ("body", "query", "path", "header"):
        parts = parts[1:]
    # pydantic names union members and validator types in locations; they are not fields
    parts = [p for p in parts if not (isinstance(p, str) and (p.startswith("function-") or "[" in p
                                                              or p in ("float", "str", "int", "bool")))]
    return pointer_of(tuple(parts))

# Top-level fields of a mechanism document: a body made of them is a document sent unwrapped.
_DOCUMENT_FIELDS = {"schema_version", "units", "materials", "sections", "bodies", "elements", "loads", "outputs"}


def _unwrapped_document(body) -> bool:
    return isinstance(body, dict) and "document" not in body and "example" not in body and \
        len(_DOCUMENT_FIELDS & set(body)) >= 2


@lru_cache(maxsize=1)
def _request_field_names() -> tuple[str, ...]:
    names, stack = set(), [m for m in vars(schemas).values() if isinstance(m, type) and issubclass(m, BaseModel)]
    for model in stack:
        names.update(info.alias or name for name, info in model.model_fields.items())
    return tuple(sorted(names))


def _message(first: dict) -> str:
    message = first.get("msg", "invalid")
    if first.get("type") == "missing":
        return "required field is missing"
    if first.get("type") == "extra_forbidden":
        key = str(first.get("loc", ("",))[-1])
        close = difflib.get_close_matches(key, _request_field_names(), n=1, cutoff=0.75)
        return f"unknown field '{key}'" + (f" (did you mean '{close[0]}'?)" if close else "")
    return message[len("Value error, "):] if message.startswith("Value error, ") else message


def _on_validation_error(_request: Request, exc: RequestValidationError) -> JSONResponse:
    errors = exc.errors()
    for e in errors:
        if e.get("type") == "json_invalid":
            detail = e.get("ctx", {}).get("error", "")
            return error_response(400, "malformed_json", f"the body is not valid JSON: {detail}".rstrip(": "))
    if _unwrapped_document(getattr(exc, "body", None)):
        return error_response(422, "invalid_request", "body: this is a mechanism document itself: send it as "
                              '{"document": <the document>} (or name one of GET /v1/examples as {"example": "<name>"})',
                              "")
    first = next((e for e in errors if e.get("type") == "extra_forbidden"), errors[0])
    pointer = _validation_pointer(tuple(first.get("loc", ())))
    message = _message(first)
    others = len({_validation_pointer(tuple(e.get("loc", ()))) for e in errors} - {pointer})
    if others:
        message += f" (and {others} more field{'s' if others > 1 else ''} with problems)"
    where = pointer or "body"
    return error_response(422, "invalid_request", f"{where}: {message}", pointer)


def _on_mechanism_error(_request: Request, exc: MechanismError) -> JSONResponse:
    return error_response(422, "invalid_input", str(exc), exc.pointer)

def _on_api_error(_request: Request, exc: ApiError) -> JSONResponse:
    headers = {"WWW-Authenticate": "ApiKey"} if exc.status == 401 else None
    return error_response(exc.status, exc.code, exc.message, exc.pointer, headers)

_HTTP_CODES = {404: "not_found", 405: "method_not_allowed", 400: "bad_request", 413: "body_too_large"}

def _on_http_error(_request: Request, exc: StarletteHTTPException) -> JSONResponse:
    code = _HTTP_CODES.get(exc.status_code, "http_error")
    message = exc.detail if isinstance(exc.detail, str) else "error"
    return error_response(exc.status_code, code, message, headers=getattr(exc, "headers", None))

def _on_store_error(request: Request, exc: SQLAlchemyError) -> JSONResponse:
    log.error("job store unavailable on %s %s: %s", request.method, request.url.path, str(exc).splitlines()[0][:300])
    return error_response(503, "store_unavailable", "the job store cannot be read or written just now (the "
                          "database is locked or its disk is full): try again shortly", headers={"Retry-After": "5"})


def _on_unexpected(request: Request, exc: Exception) -> JSONResponse:
    log.exception("unhandled error on %s %s", request.method, request.url.path)
    return error_response(500, "internal_error", "internal error; it has been logged")

def install_error_handlers(app: FastAPI) -> None:
    app.add_exception_handler(RequestValidationError, _on_validation_error)
    app.add_exception_handler(MechanismError, _on_mechanism_error)
    app.add_exception_handler(ApiError, _on_api_error)
    app.add_exception_handler(StarletteHTTPException, _on_http_error)
    app.add_exception_handler(SQLAlchemyError, _on_store_error)
    app.add_exception_handler(Exception, _on_unexpected)

