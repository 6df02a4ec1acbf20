"""`flexmech trace`: the equilibrium path through limit points, by arc-length continuation."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console

from flexmech.api.cli.application import app
from flexmech.api.cli.common import (
    EXIT_NOT_CONVERGED,
    OptionError,
    check_plot_option,
    consoles,
    default_xy,
    print_left_out,
    save_plot,
    shown,
    spread,
    table_of,
    user_errors,
    write_json,
)
from flexmech.api.cli.options import DocArg, JsonOpt, SetOpt, mechanism
from flexmech.service.drawings.figures import field_label

if TYPE_CHECKING:  # continuation is imported when the command runs
    from flexmech.models import Mechanism
    from flexmech.service.solvers.continuation import PathResult

# Points of the path printed (the --json file has every one).
SHOWN_POINTS = 12


def shown_output(mech: Mechanism) -> str:
    """The output the path is shown against: the first point output's dy where there is one,
    else the y of default_xy."""
    _, y_name = default_xy(mech)
    dy = y_name.removesuffix(".y") + ".dy"
    return dy if dy in mech.graphs.output_names else y_name


def print_path(out: Console, mech: Mechanism, path: str, result: PathResult) -> None:
    """The limit points and a dozen points of the path, with the displacement of the first
    point output (shown_output) and their stability."""
    from flexmech.service.drawings.plotting import output_unit

    watched = shown_output(mech)
    field, output = f"{field_label(path)} [{result.unit}]", f"{watched} [{output_unit(mech, watched)}]"
    table = table_of("limit points", "kind", field, output, "after point")
    for lp in result.limit_points:
        table.add_row(lp.kind, lp.value, lp.outputs[watched], str(lp.after_point))
    out.print(table)
    table = table_of("path", "point", field, output, "stable")
    rows = spread(len(result.points), SHOWN_POINTS)
    for i in rows:
        pt = result.points[i]
        table.add_row(
            str(i),
            pt.value,
            pt.outputs[watched],
            {True: "yes", False: "no", None: "?"}[pt.stability.stable],
        )
    out.print(table)
    print_left_out(out, len(rows), len(result.points), "points", spread_out=True)


@app.command()
def trace(
    document: DocArg,
    path: Annotated[str, typer.Option(help="The numeric field to follow, e.g. /loads/P/force/1.")],
    stop: Annotated[float, typer.Option(help="Stop once the field passes this value (document units).")],
    step: Annotated[float, typer.Option(help="First arc-length step, document units of the field.")],
    sets: SetOpt = None,
    max_points: Annotated[int, typer.Option(min=2, max=100_000)] = 400,
    json_out: JsonOpt = None,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot",
            metavar="OUT.png|svg",
            help="Draw the field against the shown output along the path: stable "
            "stretches solid, unstable dashed, limit points marked with their value.",
        ),
    ] = None,
) -> None:
    """Pseudo-arc-length continuation of the equilibrium path through limit points (snap-through),
    with the stability of every point and the limit loads located exactly."""
    from flexmech.models import MechanismError
    from flexmech.service.solvers.continuation import trace_path

    out, err = consoles()
    with user_errors(err):
        check_plot_option(plot)
        mech = mechanism(document, None, sets)
        try:
            mech.parameter_index(path)
        except MechanismError as exc:
            raise OptionError("--path", exc.problem) from None
        if not step > 0:
            raise OptionError("--step", f"must be positive, got {step:g}")
        result = trace_path(mech, path, stop, step, max_points)
        out.print(f"[bold]{shown(mech.document.name)}[/bold]  ({shown(str(document))}): path of {path}")
        out.print(
            f"status: {result.status}, {len(result.points)} points, {result.seconds:.3g} s"
            + (f" ({shown(result.message)})" if result.message else "")
        )
        print_path(out, mech, path, result)
        if json_out is not None:
            write_json(json_out, {"document": str(document), **result.to_dict()})
            out.print(f"wrote {shown(str(json_out))}")
        if plot is not None and result.points:
            from flexmech.service.drawings.plotting import plot_trace

            save_plot(plot_trace, mech, result, shown_output(mech), plot)
            out.print(f"wrote {shown(str(plot))}")
    if result.status != "completed":
        raise typer.Exit(EXIT_NOT_CONVERGED)
