"""`flexmech batch`: every document of a folder, by the analysis it declares, to a folder of
results (another folder than the input's)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console

from flexmech.api.cli.application import app
from flexmech.api.cli.common import EXIT_NOT_CONVERGED, OptionError, consoles, shown, table_of, user_errors
from flexmech.api.cli.options import JacobianOpt, LineSearchOpt, MaxIterOpt, newton_options

if TYPE_CHECKING:  # the solvers are imported when the command runs
    from flexmech.service.solvers.newton import NewtonOptions


def run_with_progress(
    err: Console, directory: Path, out: Path, options: NewtonOptions, count: int, chosen=None
) -> dict:
    """service.batch.run_batch with a progress bar on stderr; its summary."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from flexmech.service.batch import run_batch

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    with Progress(*columns, console=err, transient=True) as bar:
        task = bar.add_task("batch", total=count)

        def advance(path: Path, payload: dict) -> None:
            bar.update(task, advance=1, description=path.name)

        return run_batch(directory, out, options, advance, chosen)


def print_summary(console: Console, summary: dict, out: Path) -> None:
    """One row per document (green when it succeeded, by service.batch.succeeded), then the
    message of each that failed."""
    from flexmech.service.batch import succeeded

    table = table_of(
        f"{summary['documents']} documents -> {out}", "document", "analysis", "status", "result", "seconds", text=4
    )
    rows = [(row, succeeded(row["analysis"], row["status"])) for row in summary["results"]]
    for row, ok in rows:
        colour = "green" if ok else "red"
        table.add_row(
            shown(row["document"]),
            str(row["analysis"] or "-"),
            f"[{colour}]{shown(row['status'])}[/{colour}]",
            shown(row["result"]),
            f"{row['seconds']:.3g}",
        )
    console.print(table)
    for row in (row for row, ok in rows if not ok):
        console.print(f"[red]{shown(row['document'])}:[/red] {shown(row['message'])}")
    console.print(f"wrote {shown(str(out / 'summary.json'))}")


def _given(text: str | None) -> dict:
    import json

    try:
        given = json.loads(text) if text is not None else {}
    except json.JSONDecodeError as exc:
        raise OptionError("--options", f"not JSON: {exc.msg}") from None
    if not isinstance(given, dict):
        raise OptionError("--options", "expected a JSON object")
    return given


def chosen_export(text: str | None):
    """The export the flags choose: --options are the fields of POST /v1/exports (name, inputs,
    outputs, ranges, target, max_iterations, tolerance, line_search_halvings)."""
    from pydantic import ValidationError

    from flexmech.models.errors import pointer_of
    from flexmech.service.batch import Export
    from flexmech.service.jobs.export import ExportJobOptions

    try:
        return Export(ExportJobOptions.model_validate(_given(text)))
    except ValidationError as exc:
        first = exc.errors()[0]
        raise OptionError(f"--options {pointer_of(tuple(first['loc']))}", first["msg"]) from None


def chosen_analysis(name: str | None, text: str | None):
    """The analysis and its typed options the flags choose (None: each document's own)."""
    if name is None:
        if text is not None:
            raise OptionError("--options", "options are those of an analysis: give --analysis too")
        return None
    from flexmech.models import MechanismError
    from flexmech.service.analyses import ANALYSES
    from flexmech.service.batch import Chosen

    try:
        analysis = ANALYSES.named(name)
    except MechanismError as exc:
        raise OptionError("--analysis", exc.problem) from None
    given = _given(text)
    try:
        return Chosen(analysis, analysis.options_of(given))
    except MechanismError as exc:
        raise OptionError(f"--options {exc.pointer}", exc.problem) from None


AnalysisOpt = Annotated[
    str | None,
    typer.Option(
        "--analysis",
        help="Run this analysis of every document instead of the one each declares "
        "(any of `flexmech solve --analysis`, a plugin's included).",
        show_default=False,
    ),
]
OptionsOpt = Annotated[
    str | None,
    typer.Option(
        "--options",
        metavar="JSON",
        help="The analysis' options (its fields of POST /v1/solve), or with --export the export's (its "
        "fields of POST /v1/exports), as a JSON object.",
        show_default=False,
    ),
]
ExportOpt = Annotated[
    bool,
    typer.Option(
        "--export",
        help="Export every document's solver as a C99 library (as `flexmech export`) into OUT/c/<stem>/ "
        "instead of analysing it (build one with make -C OUT/c/<stem>).",
    ),
]


@app.command()
def batch(
    directory: Annotated[
        Path, typer.Argument(help="Folder of mechanism documents (JSON or YAML).", show_default=False)
    ],
    out: Annotated[Path, typer.Option("--out", help="Folder for the results (created).")],
    jacobian: JacobianOpt = "full",
    line_search: LineSearchOpt = True,
    max_iterations: MaxIterOpt = 50,
    analysis: AnalysisOpt = None,
    analysis_options: OptionsOpt = None,
    export: ExportOpt = False,
) -> None:
    """Run every document of a folder through the analysis it declares (its optimize section,
    else its inverse section, else its sweep, else the equilibrium), or through --analysis with
    --options, or export each as a C library (--export); write one result file per
    document (<stem>.json, or <file name>.json when stems clash) and summary.json. Exit 1 if
    any document failed; the others are still written. Exit 2 if --out is the input folder."""
    from flexmech.service.batch import batch_documents, same_folder

    out_console, err = consoles()
    with user_errors(err):
        if not directory.is_dir():
            raise OptionError("DIRECTORY", f"'{directory}' is not a folder")
        options = newton_options(jacobian, line_search, max_iterations)
        if export and analysis is not None:
            raise OptionError("--export", "an export is the run of every document: give --export or --analysis")
        chosen = chosen_export(analysis_options) if export else chosen_analysis(analysis, analysis_options)
        documents = batch_documents(directory)
        if not documents:
            raise OptionError("DIRECTORY", f"no documents (*.json, *.yaml) in '{directory}'")
        if same_folder(directory, out):
            raise OptionError(
                "--out",
                f"'{out}' is the input folder: the results would overwrite its documents; choose another folder",
            )
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OptionError("--out", f"cannot create {out}: {exc.strerror}") from None
        summary = run_with_progress(err, directory, out, options, len(documents), chosen)
        print_summary(out_console, summary, out)
    if summary["failed"]:
        raise typer.Exit(EXIT_NOT_CONVERGED)
