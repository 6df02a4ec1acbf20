"""What every command shares: the consoles, tables and numbers it prints, the one-line errors
and exit codes, and the files it writes."""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

import typer
from rich.console import Console
from rich.markup import escape

from flexmech.api.cli.quantities import TextTable, number, without_controls  # noqa: F401 (number: for commands)
from flexmech.service.drawings.figures import PLOT_SUFFIXES

if TYPE_CHECKING:  # the models are imported when a command runs
    from flexmech.models import Mechanism

EXIT_NOT_CONVERGED = 1
EXIT_ERROR = 2
FILE_WIDTH = 160


class OptionError(Exception):
    """A command-line option that cannot be used; `where` names the option."""

    def __init__(self, where: str, problem: str):
        self.where = where
        self.problem = problem
        super().__init__(f"{where}: {problem}")

    def __reduce__(self):
        return (OptionError, (self.where, self.problem))


# --- console and errors --------------------------------------------------------------------
def consoles() -> tuple[Console, Console]:
    """(stdout, stderr) consoles, made per command so they follow the current streams. Output
    that is not a terminal (a file, a pipe) gets wide lines rather than squeezed tables,
    unless COLUMNS says otherwise."""
    out = Console()
    if not out.is_terminal and "COLUMNS" not in os.environ:
        out = Console(width=FILE_WIDTH)
    return out, Console(stderr=True, highlight=False)


def table_of(title: str | None, *columns: str, text: int = 1, unit_column: tuple[int, int] | None = None) -> TextTable:
    """A table whose first `text` columns are words and the others numbers (right-aligned,
    folded rather than cut when the console is narrow). Numbers given as numbers are shown in
    their column's display unit (api.cli.quantities); `unit_column` (value column, unit
    column) when the unit varies by row."""
    table = TextTable(title=shown(title) if title else None, title_justify="left", unit_column=unit_column)
    for k, head in enumerate(columns):
        if k < text:
            table.add_column(shown(head), raw=head)
        else:
            table.add_column(shown(head), raw=head, justify="right", overflow="fold")
    return table


def user_error_types() -> tuple[type[Exception], ...]:
    """OptionError, and MechanismError once the models are imported (none is raised before)."""
    errors = sys.modules.get("flexmech.models.errors")
    return (OptionError,) if errors is None else (OptionError, errors.MechanismError)


@contextmanager
def user_errors(err: Console) -> Iterator[None]:
    """Turn problems with the document or the options into one red line and exit code 2."""
    try:
        yield
    except user_error_types() as exc:  # evaluated when an exception arrives
        print_error(err, str(exc))
        raise typer.Exit(EXIT_ERROR) from None


def shown(text: str) -> str:
    """A string from a document, a report or a message, for the terminal: text, never rich
    markup, its control characters as spaces (an escape sequence in a name would be a command
    to the terminal: a title, the clipboard, lines overwritten), its line ends and tabs kept."""
    return escape(without_controls(text))


def print_error(err: Console, text: str) -> None:
    """The one line "error: <where>: <problem>"."""
    err.print(f"[bold red]error:[/bold red] {shown(text)}", soft_wrap=True)


def spread(count: int, kept: int) -> list[int]:
    """The indices of at most `kept` of `count` rows, spread evenly, the first and the last
    among them (every row when there are no more than `kept`)."""
    if count <= kept:
        return list(range(count))
    return sorted({round(k * (count - 1) / (kept - 1)) for k in range(kept)})


def left_out(kept: int, total: int, what: str, spread_out: bool = False) -> str | None:
    """The line under a table that shows `kept` of `total` rows (None when it shows them all):
    "... and 14 more impacts (--json has them all)", or for rows spread over the whole
    ("12 of 400 points shown, spread evenly (--json has them all)")."""
    if kept >= total:
        return None
    if spread_out:
        return f"{kept} of {total} {what} shown, spread evenly (--json has them all)"
    return f"... and {total - kept} more {what} (--json has them all)"


def print_left_out(out: Console, kept: int, total: int, what: str, spread_out: bool = False) -> None:
    line = left_out(kept, total, what, spread_out)
    if line is not None:
        out.print(shown(line), style="dim")


# --- files ---------------------------------------------------------------------------------
def write_json(path: Path, payload: dict) -> None:
    from flexmech.service.solvers.reports import plain

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(plain(payload), indent=2))
    except OSError as exc:
        raise OptionError("--json", f"cannot write {path}: {exc.strerror}") from None


def check_plot_option(plot: Path | None) -> None:
    if plot is not None and plot.suffix.lower() not in PLOT_SUFFIXES:
        raise OptionError(
            "--plot", f"cannot tell the figure format of '{plot}': use a name ending in {' or '.join(PLOT_SUFFIXES)}"
        )


def save_plot(draw, *args, **options) -> None:
    """draw(*args, **options), whose last positional argument is the file."""
    try:
        draw(*args, **options)
    except OSError as exc:
        raise OptionError("--plot", f"cannot write {args[-1]}: {exc.strerror}") from None


# --- outputs -------------------------------------------------------------------------------
def default_xy(mech: Mechanism) -> tuple[str, str]:
    """The outputs to plot by default: the first point output, else the first body that is
    not fixed."""
    if mech.structure.points:
        name = mech.structure.points[0].name
    else:
        free = [b for b, row in enumerate(mech.structure.prescribed) if any(v is None for v in row)]
        name = f"bodies.{mech.structure.bodies[free[0] if free else 0]}"
    return f"{name}.x", f"{name}.y"


# A prescribed displacement component, the reaction component and body coordinate along it.
REACTION_ALONG = {"dx": "Fx", "dy": "Fy", "rotation": "M"}
COORDINATE_ALONG = {"dx": "x", "dy": "y", "rotation": "angle"}


def prescribed_motion(mech: Mechanism, pointer: str) -> tuple[str, str] | None:
    """(body, component) when `pointer` is a prescribed displacement, /loads/<name>/dx, dy or
    rotation, of a displacement load; else None."""
    parts = pointer.split("/")
    if len(parts) != 4 or parts[0] or parts[1] != "loads" or parts[3] not in REACTION_ALONG:
        return None
    load = mech.document.loads.get(parts[2])
    if load is None or load.type != "displacement":
        return None
    return load.body, parts[3]


def reaction_along(mech: Mechanism, pointer: str) -> list[str]:
    """The reaction components along the prescribed displacement `pointer` (none if it is
    not one): those of the document's reaction outputs of its body, then the built-in
    reactions.<body>."""
    motion = prescribed_motion(mech, pointer)
    if motion is None:
        return []
    body, component = motion
    names = [
        f"{name}.{REACTION_ALONG[component]}"
        for name, spec in mech.document.outputs.items()
        if spec.type == "reaction" and spec.body == body
    ]
    names.append(f"reactions.{body}.{REACTION_ALONG[component]}")
    return [name for name in names if name in mech.graphs.output_names]


def displacement_xy(mech: Mechanism, pointer: str) -> tuple[str, str] | None:
    """The outputs to plot by default for a sweep of the prescribed displacement `pointer`:
    the moved body's displacement along it (its first point output's dx or dy, else the
    body's x, y or angle) and the reaction along it (reaction_along). None if `pointer` is no
    prescribed displacement."""
    reactions = reaction_along(mech, pointer)
    if not reactions:
        return None
    body, component = prescribed_motion(mech, pointer)
    points = [pt.name for pt in mech.structure.points if mech.structure.bodies[pt.body] == body]
    if points and component != "rotation":
        return f"{points[0]}.{component}", reactions[0]
    return f"bodies.{body}.{COORDINATE_ALONG[component]}", reactions[0]


def output_hint(mech: Mechanism) -> str:
    """The first named outputs, for a message about an unknown one."""
    names = [n for n in mech.graphs.output_names if not n.startswith("elements.")]
    return "outputs: " + ", ".join(names[:12]) + (", ..." if len(names) > 12 else "")
