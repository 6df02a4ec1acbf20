"""The options several commands take, and what they build: the mechanism (document, model,
--set overrides) and the Newton options."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from flexmech.api.cli.catalog import MODEL_NAMES
from flexmech.api.cli.common import OptionError
from flexmech.api.cli.problems import every_problem

if TYPE_CHECKING:  # the models and the solvers are imported when a command runs
    from flexmech.models import Mechanism
    from flexmech.service.solvers.newton import NewtonOptions

JACOBIANS = ("full", "first_term", "frozen")
RESTARTS = ("previous", "undeformed")


def document_argument(given: str) -> Path:
    """The DOCUMENT argument: a file, or the name of a shipped example (`flexmech examples`)."""
    from flexmech.models import MechanismError
    from flexmech.service.examples import document_path

    try:
        return document_path(given)
    except MechanismError as exc:
        raise typer.BadParameter(exc.problem) from None


DocArg = Annotated[
    Path,
    typer.Argument(
        help="Mechanism document (JSON or YAML), or an example's name (gripper: flexmech examples lists them).",
        show_default=False,
        parser=document_argument,
    ),
]
ModelOpt = Annotated[
    str | None,
    typer.Option(
        "--model", help=f"Model of every curved beam: {' | '.join(MODEL_NAMES)} (default: as in the document)."
    ),
]
SetOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--set",
        metavar="POINTER=VALUE",
        help='Override a numeric field, in document units or as a quantity ("5 um"). Repeatable.',
    ),
]
JacobianOpt = Annotated[
    str,
    typer.Option(
        "--jacobian",
        help=f"Newton matrix: {' | '.join(JACOBIANS)} (K_T, its first term, or K_T frozen at the undeformed state).",
    ),
]
LineSearchOpt = Annotated[bool, typer.Option("--line-search/--no-line-search", help="Backtracking line search.")]
MaxIterOpt = Annotated[int, typer.Option("--max-iterations", help="Newton iterations per solve.")]
JsonOpt = Annotated[Path | None, typer.Option("--json", metavar="OUT.json", help="Write the results as JSON.")]
PlotOpt = Annotated[Path | None, typer.Option("--plot", metavar="OUT.png|svg", help="Write a figure.")]


def choice(option: str, value: str | None, choices: tuple[str, ...]) -> None:
    if value is not None and value not in choices:
        raise OptionError(option, f"unknown choice '{value}' (choose from {', '.join(choices)})")


def overrides(sets: list[str] | None) -> dict[str, float | str]:
    """--set POINTER=VALUE items: VALUE as a number (document units) or a quantity string."""
    out: dict[str, float | str] = {}
    for item in sets or []:
        pointer, sep, value = item.partition("=")
        pointer, value = pointer.strip(), value.strip()
        if not sep or not pointer or not value:
            raise OptionError("--set", f"expected POINTER=VALUE, got '{item}'")
        if not pointer.startswith("/"):
            raise OptionError("--set", f"'{pointer}' is not a JSON pointer (like /loads/actuation/force/1)")
        try:
            out[pointer] = float(value)
        except ValueError:
            out[pointer] = value
    return out


def mechanism(document: Path, model: str | None, sets: list[str] | None) -> Mechanism:
    """The compiled mechanism of the document, its overrides applied; MechanismError saying
    every problem the document's reading found (api.cli.problems)."""
    from flexmech.models import MODELS, MechanismError, compile_mechanism, load_document

    choice("--model", model, MODELS)
    given = overrides(sets)
    try:
        mech = compile_mechanism(load_document(document), model=model)
    except MechanismError as exc:
        raise every_problem(exc) from None
    return mech.with_values(given) if given else mech


def newton_options(jacobian: str, line_search: bool, max_iterations: int) -> NewtonOptions:
    from flexmech.service.solvers.newton import NewtonOptions

    choice("--jacobian", jacobian, JACOBIANS)
    if max_iterations < 1:
        raise OptionError("--max-iterations", f"must be at least 1, got {max_iterations}")
    return NewtonOptions(max_iterations=max_iterations, line_search=line_search, jacobian=jacobian)
