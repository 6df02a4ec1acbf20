"""`flexmech batch`: every document of a folder to a folder of results."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape

from service.cli.application import app
from service.cli.common import EXIT_NOT_CONVERGED, OptionError, consoles, table_of, user_errors
from service.cli.options import JacobianOpt, LineSearchOpt, MaxIterOpt, newton_options
from service.newton import NewtonOptions


def run_with_progress(err: Console, directory: Path, out: Path, options: NewtonOptions, count: int) -> dict:
    """service.batch.run_batch with a progress bar on stderr; its summary."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from service.batch import run_batch

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    with Progress(*columns, console=err, transient=True) as bar:
        task = bar.add_task("batch", total=count)

        def advance(path: Path, payload: dict) -> None:
            bar.update(task, advance=1, description=path.name)

        return run_batch(directory, out, options, advance)


def print_summary(console: Console, summary: dict, out: Path) -> None:
    """One row per document, then the message of each that failed."""
    table = table_of(f"{summary['documents']} documents -> {out}", "document", "analysis", "status", "seconds",
                     text=3)
    for row in summary["results"]:
        colour = "green" if row["status"] == "converged" else "red"
        table.add_row(escape(row["document"]), str(row["analysis"] or "-"),
                      f"[{colour}]{row['status']}[/{colour}]", f"{row['seconds']:.3g}")
    console.print(table)
    for row in summary["results"]:
        if row["status"] != "converged":
            console.print(f"[red]{escape(row['document'])}:[/red] {escape(row['message'])}")
    console.print(f"wrote {escape(str(out / 'summary.json'))}")


@app.command()
def batch(
    directory: Annotated[Path, typer.Argument(help="Folder of mechanism documents (JSON or YAML).", show_default=False)],
    out: Annotated[Path, typer.Option("--out", help="Folder for the results (created).")],
    jacobian: JacobianOpt = "full",
    line_search: LineSearchOpt = True,
    max_iterations: MaxIterOpt = 50,
) -> None:
    """Solve every document of a folder (sweep it, if it declares a sweep); write one result file
    per document and summary.json. Exit 1 if any document failed; the others are still written."""
    from service.batch import batch_documents

    out_console, err = consoles()
    with user_errors(err):
        if not directory.is_dir():
            raise OptionError("DIRECTORY", f"'{directory}' is not a folder")
        options = newton_options(jacobian, line_search, max_iterations)
        documents = batch_documents(directory)
        if not documents:
            raise OptionError("DIRECTORY", f"no documents (*.json, *.yaml) in '{directory}'")
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OptionError("--out", f"cannot create {out}: {exc.strerror}") from None
        summary = run_with_progress(err, directory, out, options, len(documents))
        print_summary(out_console, summary, out)
    if summary["failed"]:
        raise typer.Exit(EXIT_NOT_CONVERGED)
