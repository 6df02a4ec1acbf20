"""The bounds on a document's text, checked on the raw JSON before any model reads it (issue 52).

The document's models bound every text field (models.documents.fields); this check is the fast
guard a server runs on the request's own thread, before a worker is involved: one pass over
the parsed JSON, without recursion (a deep body cannot overflow it) and without copying a
string, that refuses the first text over its bound:

    /name           over MAX_NAME_CHARS          (200)
    /description    over MAX_DESCRIPTION_CHARS   (20,000)
    any key         over MAX_KEY_CHARS           (256: the longest a key of any collection may be)
    any other text  over MAX_DESCRIPTION_CHARS

It is never stricter than the models where they bound a text (a field's own, tighter bound is
theirs to tell); inside free-form values (a history's table, an inverse's shapes) it is the only
bound. Messages name the bound and the length, never the text itself.
"""

from __future__ import annotations

from typing import Any

from flexmech.models.documents.fields import (
    MAX_DESCRIPTION_CHARS,
    MAX_NAME_CHARS,
    MAX_OUTPUT_CHARS,
    MAX_POINTER_CHARS,
)
from flexmech.models.errors import MechanismError, pointer_of

# keys are names (bodies, elements, ...), JSON pointers (overrides, tolerances' fields) or
# output names (tolerances' specs)
MAX_KEY_CHARS = max(MAX_NAME_CHARS, MAX_POINTER_CHARS, MAX_OUTPUT_CHARS)
TOP_LEVEL_BOUNDS = {"name": MAX_NAME_CHARS, "description": MAX_DESCRIPTION_CHARS}


def too_long(limit: int, length: int, key: bool = False) -> str:
    """What is wrong with a text (or a key) of `length` characters over its `limit`."""
    if key:
        return f"a key of {length} characters: keys here are at most {limit} characters"
    return f"at most {limit} characters (got {length})"


def longer_than_any(length: int) -> str:
    """A text longer than any of a document may be (its field's own bound may be far lower)."""
    return f"a text of {length} characters: no text of a document may be longer than {MAX_DESCRIPTION_CHARS}"


def check_text_bounds(document: Any, prefix: str = "") -> None:
    """Raise MechanismError naming the first text of a parsed JSON document over its bound (its
    pointer under `prefix`, e.g. /document in a request): a key's error names the object that
    holds it. Anything else about the document is left to its models."""
    if isinstance(document, dict):
        for field, limit in TOP_LEVEL_BOUNDS.items():
            value = document.get(field)
            if isinstance(value, str) and len(value) > limit:
                raise MechanismError(f"{prefix}/{field}", too_long(limit, len(value)))
    stack: list[tuple[Any, tuple | None]] = [(document, None)]  # a value, and where: (its parent's where, key)
    while stack:
        value, where = stack.pop()
        if isinstance(value, dict):
            for key in value:
                if isinstance(key, str) and len(key) > MAX_KEY_CHARS:
                    raise MechanismError(prefix + _pointer(where), too_long(MAX_KEY_CHARS, len(key), key=True))
            stack.extend((item, (where, key)) for key, item in reversed(value.items()))
        elif isinstance(value, list):
            stack.extend((value[k], (where, k)) for k in range(len(value) - 1, -1, -1))
        elif isinstance(value, str) and len(value) > MAX_DESCRIPTION_CHARS:
            raise MechanismError(prefix + _pointer(where), longer_than_any(len(value)))


def _pointer(where: tuple | None) -> str:
    """The JSON pointer of a place the walk keeps as (its parent's place, its key), built only
    for an error (a path per value would cost the depth each)."""
    parts = []
    while where is not None:
        where, key = where
        parts.append(key)
    return pointer_of(tuple(reversed(parts)))
