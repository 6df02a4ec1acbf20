"""The one exception type for problems with a mechanism document."""

from __future__ import annotations


class MechanismError(ValueError):
    """A mechanism document (or an override of it) that cannot be modelled.

    ``pointer`` is the JSON pointer of the offending field ("" for the whole document) and
    ``problem`` says what is wrong with it, in words an engineer can act on. ``problems`` are
    (pointer, problem) of every field with a problem when a reader found several, this one
    first (default: this one alone).
    """

    def __init__(self, pointer: str, problem: str, problems: tuple[tuple[str, str], ...] = ()):
        self.pointer = pointer
        self.problem = problem
        self.problems = tuple(problems) or ((pointer, problem),)
        where = pointer if pointer else "document"
        super().__init__(f"{where}: {problem}")


def pointer_of(location: tuple) -> str:
    """JSON pointer (RFC 6901) of a pydantic error location."""
    parts = [str(p).replace("~", "~0").replace("/", "~1") for p in location]
    return "/" + "/".join(parts) if parts else ""
