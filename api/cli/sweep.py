"""`flexmech sweep`: a numeric field swept with continuation (the document's sweep section, or
one given by --path), for one model or each (--compare-models); the curves are run and printed
by api.cli.sweep_curves, --csv writes them as a table (api.cli.csv_files)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console

from flexmech.api.cli.application import app
from flexmech.api.cli.catalog import COMPARED_MODEL_NAMES
from flexmech.api.cli.common import EXIT_NOT_CONVERGED, consoles, save_plot, shown, user_errors, write_json
from flexmech.api.cli.options import (
    RESTARTS,
    DocArg,
    JacobianOpt,
    JsonOpt,
    LineSearchOpt,
    MaxIterOpt,
    ModelOpt,
    PlotOpt,
    SetOpt,
    mechanism,
)

if TYPE_CHECKING:  # the models and the sweep are imported when the command runs
    from flexmech.api.cli.sweep_plan import SweepPlan
    from flexmech.models import Mechanism

CsvOpt = Annotated[
    Path | None,
    typer.Option(
        "--csv",
        metavar="OUT.csv",
        help="Write every point of every curve as CSV: the swept field, each output and the status, "
        "a column each, units in the header.",
    ),
]
XOutputOpt = Annotated[
    str | None,
    typer.Option(
        "--x-output",
        help="Output on the horizontal axis (default: the first point output's x; for a prescribed displacement, the moved body's displacement along it).",
    ),
]
YOutputOpt = Annotated[
    str | None,
    typer.Option(
        "--y-output",
        help="Output on the left panel's vertical axis (default: the point's y; for a prescribed displacement, the reaction along it, and its secant stiffness is printed and drawn).",
    ),
]


# --- the command -----------------------------------------------------------------------------
@app.command()
def sweep(
    document: DocArg,
    path: Annotated[
        str | None,
        typer.Option(
            "--path", metavar="POINTER", help="Numeric field to sweep (default: the document's sweep section)."
        ),
    ] = None,
    start: Annotated[str | None, typer.Option("--start", help="First value (document units or a quantity).")] = None,
    stop: Annotated[str | None, typer.Option("--stop", help="Last value.")] = None,
    steps: Annotated[
        int | None, typer.Option("--steps", help="Number of steps (points = steps + 1); default 100.")
    ] = None,
    until: Annotated[
        str | None,
        typer.Option("--until", metavar="OUTPUT=VALUE", help="End where OUTPUT reaches VALUE, instead of --stop."),
    ] = None,
    model: ModelOpt = None,
    compare_models: Annotated[
        bool, typer.Option("--compare-models", help=f"Sweep with each model ({', '.join(COMPARED_MODEL_NAMES)}).")
    ] = False,
    restart: Annotated[
        str, typer.Option("--restart", help=f"Newton start at each point: {' | '.join(RESTARTS)}.")
    ] = "previous",
    sets: SetOpt = None,
    jacobian: JacobianOpt = "full",
    line_search: LineSearchOpt = True,
    max_iterations: MaxIterOpt = 50,
    json_out: JsonOpt = None,
    csv_out: CsvOpt = None,
    plot: PlotOpt = None,
    x_output: XOutputOpt = None,
    y_output: YOutputOpt = None,
) -> None:
    """Sweep a numeric field (a load, by default the document's sweep section) with continuation."""
    from flexmech.api.cli.sweep_curves import run_curves
    from flexmech.api.cli.sweep_plan import checked_options, plan_sweep

    out, err = consoles()
    with user_errors(err):
        options, models = checked_options(
            plot, restart, compare_models, model, path, start, stop, steps, until, jacobian, line_search, max_iterations
        )
        mechs = [mechanism(document, m, sets) for m in models]
        swept, plan = plan_sweep(mechs[0], path, start, stop, steps, until, x_output, y_output, restart)
        _print_heading(out, mechs[0], document, swept, plan)
        curves, records, failed = run_curves(out, err, mechs, models, plan, options)
        _write_files(out, document, mechs[0], swept, plan, curves, records, (json_out, csv_out, plot))
    if failed:
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _print_heading(out: Console, first: Mechanism, document: Path, swept: str, plan: SweepPlan) -> None:
    """The document, the swept field and its unit, and the restart."""
    out.print(
        f"[bold]{shown(first.document.name)}[/bold]  ({shown(str(document))}): "
        f"sweeping {shown(f'{swept} [{plan.unit}]')}, restart from {plan.restart}"
    )


def _write_files(
    out: Console,
    document: Path,
    first: Mechanism,
    swept: str,
    plan: SweepPlan,
    curves: list,
    records: list[dict],
    files: tuple[Path | None, Path | None, Path | None],
) -> None:
    """The --json file (every curve's record), the --csv file (their points) and the --plot
    figure (the curves that ran), as `files` names them."""
    json_out, csv_out, plot = files
    if json_out is not None:
        write_json(
            json_out,
            {
                "document": str(document),
                "name": first.document.name,
                "path": swept,
                "unit": plan.unit,
                "restart": plan.restart,
                "x_output": plan.x_output,
                "y_output": plan.y_output,
                "curves": records,
            },
        )
        out.print(f"wrote {shown(str(json_out))}")
    if csv_out is not None:
        from flexmech.api.cli.csv_files import sweep_columns, write_csv
        from flexmech.service.solvers.reports import output_units

        write_csv(csv_out, sweep_columns(swept, plan.unit, output_units(first), records))
        out.print(f"wrote {shown(str(csv_out))}")
    if plot is not None and curves:
        from flexmech.service.drawings.plotting import plot_sweeps

        save_plot(plot_sweeps, curves, plan.x_output, plan.y_output, swept, plot, secant=plan.stiffness)
        out.print(f"wrote {shown(str(plot))}")
