"""`flexmech simulate`: motion in time by the document's `simulate` section, with --until,
--step and the scheme from the command line over it. A progress bar follows simulated time;
--plot draws outputs and energies against time, --snapshots the links at six times,
--animation the moving links (.gif, or .mp4 when ffmpeg is installed)."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from models.documents.simulation_spec import IMPACT_SCHEMES
from service.cli.application import app
from service.cli.common import (
    EXIT_NOT_CONVERGED,
    OptionError,
    check_plot_option,
    consoles,
    number,
    table_of,
    user_errors,
    write_json,
)
from service.cli.options import DocArg, JsonOpt, PlotOpt, SetOpt, mechanism
from service.cli.progress import SimulationProgress

SHOWN_OUTPUTS = 6


@app.command()
def simulate(
    document: DocArg,
    sets: SetOpt = None,
    until: Annotated[float | None, typer.Option(help="End time (s).")] = None,
    step: Annotated[float | None, typer.Option(help="Time step (s).")] = None,
    scheme: Annotated[str | None, typer.Option(help="generalized_alpha | newmark | event_driven | moreau.")] = None,
    damping: Annotated[float | None, typer.Option(help="Mass-proportional damping (1/s).")] = None,
    max_steps: Annotated[
        int | None,
        typer.Option(
            "--max-steps",
            help="The most time steps (adaptive and "
            "impacts: accepted steps); default the service's limit, "
            "which this raises for a run on this machine.",
        ),
    ] = None,
    sensitivity: Annotated[
        list[str] | None,
        typer.Option(
            "--sensitivity",
            metavar="POINTER",
            help="event_driven: differentiate the end state by this number "
            "of the document, exactly (repeatable), e.g. /contacts/pairs/conjugate/normal/restitution.",
        ),
    ] = None,
    compiled: Annotated[
        bool,
        typer.Option(
            "--compiled",
            hidden=True,
            help="Deprecated and ignored: kernels compile in the build queue (flexmech build).",
        ),
    ] = False,
    animation: Annotated[
        Path | None, typer.Option("--animation", metavar="OUT.gif|mp4", help="Animate the links.")
    ] = None,
    snapshots: Annotated[
        Path | None, typer.Option("--snapshots", metavar="OUT.png|svg", help="Draw the links at six times.")
    ] = None,
    json_out: JsonOpt = None,
    plot: PlotOpt = None,
) -> None:
    """Motion in time: links, bodies and joints under loads and prescribed motions in time."""
    out, err = consoles()
    with user_errors(err):
        _check_figures(plot, snapshots, animation)
        mech = mechanism(document, None, sets)
        given = {"until": until, "step": step, "scheme": scheme, "damping": damping, "max_steps": max_steps}
        spec = _spec(mech, err, compiled, {**given, "sensitivities": sensitivity or None})
        if spec.scheme in IMPACT_SCHEMES:
            _impacts(mech, spec, out, err, json_out, plot, snapshots, animation)
            return
        report = _run(mech, spec, out, err, max_steps, json_out, plot, snapshots, animation)
    if report["status"] != "finished":
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _spec(mech, err, compiled: bool, given: dict):
    """The simulation spec: the document's `simulate` section with the command line's options
    over it; a note on stderr that --compiled is ignored."""
    from service.dynamics.run import simulation_spec

    if compiled:
        err.print(
            "--compiled is deprecated and ignored: element kernels are compiled by `flexmech build` (or "
            "the server's build queue) and used once built"
        )
    return simulation_spec(mech, given)


def _run(mech, spec, out, err, max_steps, json_out, plot, snapshots, animation) -> dict:
    """Links, bodies and joints in time under a progress bar: the report printed, the files
    written; the report."""
    from service.dynamics.run import MAX_STEPS, run_simulation

    with SimulationProgress(err, spec.until) as progress:  # --max-steps may raise the service's limit here
        history, report = run_simulation(mech, spec, progress=progress, max_steps=max(MAX_STEPS, max_steps or 0))
    _print(out, report)
    if json_out is not None:
        write_json(json_out, report)
    if plot is not None:
        from service.dynamics.figures import plot_history

        _write(plot_history, report, [n for n in report["outputs"]][:SHOWN_OUTPUTS], plot, option="--plot")
    if snapshots is not None:
        from service.dynamics.figures import draw_snapshots

        _write(draw_snapshots, mech, history, snapshots, option="--snapshots")
    if animation is not None:
        from service.dynamics.figures import animate

        _write(animate, mech, history, animation, option="--animation")
    return report


def _check_figures(plot: Path | None, snapshots: Path | None, animation: Path | None) -> None:
    """The figure options' formats, before anything runs."""
    check_plot_option(plot)
    if snapshots is not None and snapshots.suffix.lower() not in (".png", ".svg", ".pdf"):
        raise OptionError("--snapshots", f"cannot tell the figure format of '{snapshots}': use .png, .svg or .pdf")
    if animation is not None:
        suffix = animation.suffix.lower()
        if suffix not in (".gif", ".mp4"):
            raise OptionError("--animation", f"cannot tell the format of '{animation}': use .gif or .mp4")
        if suffix == ".mp4" and shutil.which("ffmpeg") is None:
            raise OptionError("--animation", "an .mp4 needs ffmpeg, which is not installed: use .gif")


def _impacts(mech, spec, out, err, json_out, plot, snapshots, animation) -> None:
    """Rigid bodies with impacts: the path of each body's mass centre and the contact forces."""
    from service.impacts.run import run_impacts

    for option, value in (("--snapshots", snapshots), ("--animation", animation)):
        if value is not None:
            raise OptionError(option, f"{option} draws links; for impacts --plot draws the motion and contact forces")
    from service.dynamics.run import MAX_STEPS

    with SimulationProgress(err, spec.until) as progress:  # the service's step limit unless --max-steps raises it
        _, report = run_impacts(mech.document, spec, progress=progress, max_steps=spec.max_steps or MAX_STEPS)
    out.print(
        f"[bold]{escape(report['name'])}[/bold]: {report['status']} at t = {report['time_reached']:g} s, "
        f"{report['steps']} steps ({spec.scheme}) in {report['seconds']:.3f} s; energy balance error "
        f"{report['energy_balance_error']:.2e}"
    )
    table = table_of(None, "impact", "pair", "time (s)", "impact speed", "exit speed", "ratio", text=2)
    for k, hit in enumerate(report["impacts"][:SHOWN_OUTPUTS]):
        table.add_row(
            str(k + 1),
            escape(hit["pair"]),
            f"{hit['time']:.7f}",
            *(number(hit[key], "") for key in ("impact_speed", "exit_speed", "rebound_ratio")),
        )
    out.print(table)
    if "sensitivities" in report:
        _print_sensitivities(out, report["sensitivities"])
    if json_out is not None:
        write_json(json_out, report)
    if plot is not None:
        from service.impacts.figures import plot_impacts

        _write(plot_impacts, report, plot, option="--plot")
    if report["status"] != "finished":
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _print_sensitivities(out, sensitivities: dict) -> None:
    """d (coordinate at the end time) / d field, a row per field."""
    fields = sensitivities["fields"]
    names = list(next(iter(fields.values()))["coordinates"]) if fields else []
    table = table_of(
        f"d (state at t = {sensitivities['time']:g} s) / d field; {sensitivities['units']['coordinates']}",
        "field",
        "unit",
        *names,
        text=2,
    )
    for pointer, values in fields.items():
        row = [number(values["coordinates"][name], "") for name in names]
        table.add_row(escape(pointer), escape(values["unit"]), *row)
    out.print(table)
    for warning in sensitivities["warnings"]:
        out.print(f"[yellow]warning:[/yellow] {escape(warning)}")


def _write(draw, *args, option: str) -> None:
    try:
        draw(*args)
    except OSError as exc:
        raise OptionError(option, f"cannot write {args[-1]}: {exc.strerror}") from None


def _print(out, report: dict) -> None:
    out.print(
        f"[bold]{escape(report['name'])}[/bold]: {report['status']} at t = {report['time_reached']:g} s, "
        f"{report['steps']} steps in {report['seconds']:.2f} s; energy balance error "
        f"{report['energy_balance_error']:.2e}"
    )
    if report["message"]:
        out.print(escape(report["message"]))
    table = table_of(None, "output", "start", "end", "min", "max", text=1)
    for name, values in list(report["outputs"].items())[: 3 * SHOWN_OUTPUTS]:
        table.add_row(escape(name), *(number(v, "") for v in (values[0], values[-1], min(values), max(values))))
    out.print(table)
