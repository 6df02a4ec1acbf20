"""A request's mechanism and options, checked: every problem is a MechanismError whose pointer
is relative to the request (the document's fields under /document), so the HTTP layer, the
CLI and the job kinds report the same field."""

from __future__ import annotations

import json
import threading
from collections import OrderedDict
from dataclasses import fields
from typing import Any

from flexmech.models import MODELS, Mechanism, MechanismError, compile_mechanism
from flexmech.models.documents.document import parse_document
from flexmech.service.costs import Limits, check_document_cost
from flexmech.service.solvers.newton import NewtonOptions

__all__ = ["Limits", "compile_request", "escape_pointer_part", "newton_options", "under"]


def escape_pointer_part(part: str) -> str:
    return str(part).replace("~", "~0").replace("/", "~1")


def under(prefix: str, exc: MechanismError) -> MechanismError:
    """The same error, its pointer placed under `prefix` (e.g. /document)."""
    return MechanismError(prefix + exc.pointer, exc.problem, tuple((prefix + p, m) for p, m in exc.problems))


def newton_options(options: dict | None, time_limit: float | None = None, pointer: str = "/options") -> NewtonOptions:
    """NewtonOptions from a request's options object; unknown or bad options name the field.
    The service's time limit caps any time limit asked for."""
    options = dict(options or {})
    known = {f.name for f in fields(NewtonOptions)}
    for name in options:
        if name not in known:
            raise MechanismError(
                f"{pointer}/{escape_pointer_part(name)}", f"unknown option (options: {', '.join(sorted(known))})"
            )
    asked = options.get("time_limit")
    if time_limit is not None:
        options["time_limit"] = time_limit if asked is None else min(float(asked), time_limit)
    try:
        return NewtonOptions(**options)
    except (TypeError, ValueError) as exc:
        name = str(exc).split(":", 1)[0] if ":" in str(exc) else ""
        field = f"{pointer}/{name}" if name in known else pointer
        raise MechanismError(field, str(exc).split(": ", 1)[-1]) from None


COMPILED_KEPT = 32  # mechanisms kept per thread: compiling the gripper costs about as much as solving it
_COMPILED: OrderedDict[tuple, Mechanism] = OrderedDict()
_LOCK = threading.Lock()  # threads share the dictionary, never a mechanism (its graphs are CasADi's)


def compile_request(
    document: dict, model: str | None = None, overrides: dict[str, Any] | None = None, limits: Limits = Limits()
) -> Mechanism:
    """Validate and compile a request's document, with its model choice and overrides. The
    compiled mechanism of a document is kept (by its text, the model and the limits), so a
    design tool sending the same document with other overrides compiles it once."""
    try:
        key = (json.dumps(document, sort_keys=True, allow_nan=False), model, limits, threading.get_ident())
    except (TypeError, ValueError):  # not JSON text (YAML's dates, NaN): compiled, then refused or kept apart
        key = None
    with _LOCK:
        mech = _COMPILED.get(key) if key is not None else None
        if mech is not None:
            _COMPILED.move_to_end(key)
    if mech is None:
        mech = _compile(document, model, limits)
        if key is not None:
            with _LOCK:
                if len(_COMPILED) >= COMPILED_KEPT:
                    _COMPILED.popitem(last=False)
                _COMPILED[key] = mech
    for pointer, value in (overrides or {}).items():
        try:
            mech = mech.with_values({pointer: value})
        except MechanismError as exc:
            raise MechanismError(f"/overrides/{escape_pointer_part(pointer)}", exc.problem) from None
    return mech


def _compile(document: dict, model: str | None, limits: Limits) -> Mechanism:
    try:
        doc = parse_document(document)
    except MechanismError as exc:
        raise under("/document", exc) from None
    if model is not None and model not in MODELS:
        raise MechanismError("/model", f"unknown model '{model}' ({', '.join(MODELS)})")
    check_document_cost(doc, model, limits)
    try:
        return compile_mechanism(doc, model)
    except MechanismError as exc:
        raise under("/document", exc) from None
