"""`flexmech simulate`: motion in time by the document's `simulate` section, with --until,
--step and the scheme from the command line over it. Progress follows the whole run (the steps,
then building the report and writing each file); --every keeps every n-th step in the report;
--json writes the report, --csv its histories, --plot draws outputs and energies against time,
--snapshots the links at six times, --animation the moving links (.gif, or .mp4 when ffmpeg is
installed). The summary and files: api.cli.simulate_output."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Annotated

import typer

from flexmech.api.cli.application import app
from flexmech.api.cli.common import EXIT_NOT_CONVERGED, OptionError, check_plot_option, consoles, user_errors
from flexmech.api.cli.options import DocArg, JsonOpt, PlotOpt, SetOpt, mechanism
from flexmech.api.cli.progress import SimulationProgress
from flexmech.api.cli.simulate_output import Files, print_impacts, print_run, write_files

EveryOpt = Annotated[
    int | None,
    typer.Option(
        "--every",
        metavar="N",
        help="Keep every N-th step in the report, its histories and frames (the first and the last "
        "always; impacts: and the states around each contact event); the steps themselves are unchanged.",
    ),
]
MaxPointsOpt = Annotated[
    int | None,
    typer.Option(
        "--max-points",
        help="Impacts (event_driven, moreau): the most states the report keeps, spread over the run "
        "(after --every), besides those around each contact event.",
    ),
]
CsvOpt = Annotated[
    Path | None,
    typer.Option(
        "--csv",
        metavar="OUT.csv",
        help="Write the histories as CSV: the time and every output, a column each, units in the header.",
    ),
]


BuildOpt = Annotated[
    bool,
    typer.Option(
        "--build/--no-build",
        help="Compile the document's kernels beside the run when they are missing: a long run restarts "
        "compiled, a short one finishes interpreted and leaves them compiled for the next.",
    ),
]


AccuracyOpt = Annotated[
    float | None,
    typer.Option(
        help="Refine the links' elements and the steps until the named outputs' (/simulate/outputs) "
        "estimated errors, relative to their excursions, are within this; report the estimates."
    ),
]
MaxStepsOpt = Annotated[
    int | None,
    typer.Option(
        "--max-steps",
        help="The most time steps (adaptive and "
        "impacts: accepted steps); default the service's limit, "
        "which this raises for a run on this machine.",
    ),
]
SCHEMES = "generalized_alpha | newmark | sdirk4 | event_driven | moreau."


@app.command()
def simulate(
    document: DocArg,
    sets: SetOpt = None,
    until: Annotated[float | None, typer.Option(help="End time (s).")] = None,
    step: Annotated[float | None, typer.Option(help="Time step (s).")] = None,
    scheme: Annotated[str | None, typer.Option(help=SCHEMES)] = None,
    damping: Annotated[float | None, typer.Option(help="Mass-proportional damping (1/s).")] = None,
    accuracy: AccuracyOpt = None,
    max_steps: MaxStepsOpt = None,
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
    build: BuildOpt = True,
    animation: Annotated[
        Path | None, typer.Option("--animation", metavar="OUT.gif|mp4", help="Animate the links.")
    ] = None,
    snapshots: Annotated[
        Path | None, typer.Option("--snapshots", metavar="OUT.png|svg", help="Draw the links at six times.")
    ] = None,
    every: EveryOpt = None,
    max_points: MaxPointsOpt = None,
    json_out: JsonOpt = None,
    csv_out: CsvOpt = None,
    plot: PlotOpt = None,
) -> None:
    """Motion in time: links, bodies and joints under loads and prescribed motions in time."""
    out, err = consoles()
    with user_errors(err):
        _check_figures(plot, snapshots, animation)
        mech = mechanism(document, None, sets)
        given = {"until": until, "step": step, "scheme": scheme, "damping": damping, "max_steps": max_steps}
        given |= {"accuracy": accuracy}
        given |= {"every": every, "max_points": max_points, "sensitivities": sensitivity or None}
        spec = _spec(mech, err, compiled, given)
        files = Files(json_out, csv_out, plot, snapshots, animation)
        report = _run(mech, spec, out, err, max_steps, files, document if build else None)
    if report["status"] != "finished":
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _spec(mech, err, compiled: bool, given: dict):
    """The simulation spec: the document's `simulate` section with the command line's options
    over it; a note on stderr that --compiled is ignored."""
    from flexmech.service.dynamics.run import simulation_spec

    if compiled:
        err.print(
            "--compiled is deprecated and ignored: element kernels are compiled by `flexmech build` (or "
            "the server's build queue) and used once built"
        )
    return simulation_spec(mech, given)


def _run(mech, spec, out, err, max_steps: int | None, files: Files, document: Path | None) -> dict:
    """The run under its progress (links, bodies and joints; or rigid bodies with impacts), its
    files written, its summary printed; the report. The service's step limit applies unless
    --max-steps raises it. `document`: compile its missing kernels beside a links' run
    (api.cli.kernels_first); None: run with what is compiled."""
    from flexmech.models.documents.simulation_spec import IMPACT_SCHEMES
    from flexmech.service.dynamics.run import MAX_STEPS

    impacts = spec.scheme in IMPACT_SCHEMES
    if impacts:
        for option, value in (("--snapshots", files.snapshots), ("--animation", files.animation)):
            if value is not None:
                raise OptionError(
                    option, f"{option} draws links; for impacts --plot draws the motion and contact forces"
                )
        with SimulationProgress(err, spec.until) as progress:
            from flexmech.service.impacts.run import run_impacts

            _, report = run_impacts(
                mech.document, spec, progress=progress.stepping(), max_steps=spec.max_steps or MAX_STEPS
            )
            write_files(progress, files, report, mech, None)
            progress.finish(_summary(report), _stepping(report))
        print_impacts(out, report, spec.scheme)
        return report
    report = _links(mech, spec, err, max(MAX_STEPS, max_steps or 0), files, document)
    print_run(out, report)
    return report


def _links(mech, spec, err, limit: int, files: Files, document: Path | None) -> dict:
    """A links' run: interpreted beside its kernels' build when they are missing (restarted
    compiled when that ends sooner), else with what is compiled."""
    from flexmech.api.cli.kernels_first import KernelBuild, Pace, missing_kernels
    from flexmech.api.cli.progress import seconds_text
    from flexmech.service.dynamics.run import run_simulation

    missing = missing_kernels(mech) if document is not None else None
    build = KernelBuild(document, missing.seconds) if missing is not None and missing.parts else None
    try:
        with SimulationProgress(
            err, spec.until, "simulating" if build is None else "simulating interpreted"
        ) as progress:
            pace = Pace(spec.until, build) if build is not None else None
            heard = progress.stepping()
            stepped = (lambda t, steps=None: (heard(t, steps), pace.heard(t, steps))) if pace is not None else heard
            history, report = run_simulation(mech, spec, stop=pace, progress=stepped, max_steps=limit)
            if pace is not None and pace.restart:
                progress.stage(f"compiling its kernels first (about {seconds_text(build.left())} more)")
                build.wait()
                progress.finish(f"stopped at t = {report['time_reached']:.4g} s to run compiled", report["seconds"])
            else:
                write_files(progress, files, report, mech, history)
                progress.finish(_summary(report), _stepping(report))
        if pace is not None and pace.restart:
            with SimulationProgress(err, spec.until, "simulating compiled") as progress:
                history, report = run_simulation(mech, spec, progress=progress.stepping(), max_steps=limit)
                write_files(progress, files, report, mech, history)
                progress.finish(_summary(report), _stepping(report))
        elif build is not None:
            err.print(
                f"ran interpreted: its kernels were not compiled (about {seconds_text(missing.seconds)} of gcc, "
                "after which runs step 2.3-4.3 times faster: the four-bar and the rod here). They are compiling now "
                f"({seconds_text(build.left())} more; Ctrl-C skips it; `flexmech build DOCUMENT` does it ahead): "
                "the next run is compiled.",
                highlight=False,
            )
            build.wait()
    finally:
        if build is not None:
            build.end()
    return report


def _summary(report: dict) -> str:
    runs = len(report["accuracy"]["runs"]) if report.get("accuracy") else 1
    checked = f" (of {runs} runs to the accuracy target)" if runs > 1 else ""
    return f"{report['status']} at t = {report['time_reached']:g} s, {report['steps']} steps{checked}"


def _stepping(report: dict) -> float:
    """The steps' time: of every run an accuracy target made."""
    return report["accuracy"]["seconds"] if report.get("accuracy") else report["seconds"]


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
