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

    def __reduce__(self):
        """Pickled with its fields: a job worker's error reaches the server as the same error
        (pickle's default would call __init__ with the message alone, and the pool would break)."""
        return (type(self), (self.pointer, self.problem, self.problems))

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and (self.pointer, self.problem, self.problems) == (
            other.pointer,  # type: ignore[attr-defined]
            other.problem,  # type: ignore[attr-defined]
            other.problems,  # type: ignore[attr-defined]
        )

    __hash__ = ValueError.__hash__


def pointer_of(location: tuple) -> str:
    """JSON pointer (RFC 6901) of a pydantic error location."""
    parts = [str(p).replace("~", "~0").replace("/", "~1") for p in location]
    return "/" + "/".join(parts) if parts else ""
