"""Problems with a document as the command line prints them: every field with a problem on a
line of its own, "error: <pointer>: <problem>" with its suggestion ("did you mean 'radius'?"),
rather than the first and a count of the others (models.documents finds them all at once;
the HTTP API lists them in its error's "problems")."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the models are imported when a command runs
    from flexmech.models import MechanismError


def every_problem(exc: MechanismError) -> MechanismError:
    """The error whose text lists each of its problems, the first where the error names it and
    the others on lines of their own below ("error: <pointer>: <problem>"): printed as the
    command line prints any error, they read as one line each."""
    from flexmech.models import MechanismError

    if len(exc.problems) <= 1:
        return exc
    (pointer, problem), *others = exc.problems
    text = problem + "".join(f"\nerror: {where or 'document'}: {what}" for where, what in others)
    return MechanismError(pointer, text, exc.problems)


def in_the_file(exc: MechanismError, prefix: str = "/document") -> MechanismError:
    """A request's problems with its document (under /document) as the file's: named from its
    root, every problem re-pointed."""
    from flexmech.models import MechanismError

    def moved(pointer: str) -> str:
        return pointer.removeprefix(prefix) if pointer == prefix or pointer.startswith(prefix + "/") else pointer

    return MechanismError(moved(exc.pointer), exc.problem, tuple((moved(p), what) for p, what in exc.problems))
