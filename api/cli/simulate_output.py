"""What `flexmech simulate` prints and writes of a run: the summary and tables (outputs, impacts,
end-state sensitivities), and the files (--json, --csv, the figures), each written as a part of
the run its progress names."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Console

from flexmech.api.cli.common import OptionError, print_left_out, shown, table_of, write_json
from flexmech.api.cli.progress import SimulationProgress, seconds_text
from flexmech.api.cli.quantities import row_texts

if TYPE_CHECKING:  # the models and the dynamics are imported when a run is written
    from flexmech.models import Mechanism
    from flexmech.service.dynamics.integrate import History

SHOWN_OUTPUTS = 18  # rows of the outputs' table
SHOWN_IMPACTS = 6  # rows of the impacts' table
PLOTTED_OUTPUTS = 6  # curves of --plot


def balance_text(error: float | None) -> str:
    """The energy balance error, a relative measure: the balance's largest change over the
    largest energy or work of the run (service.dynamics.run.with_balance)."""
    if error is None:
        return "- (no steps)"
    return f"{100 * error:.3g} % of the largest energy (relative)"


@dataclass(frozen=True)
class Files:
    """The files a run writes (None: not asked for)."""

    json: Path | None = None
    csv: Path | None = None
    plot: Path | None = None
    snapshots: Path | None = None
    animation: Path | None = None


def print_run(out: Console, report: dict[str, Any]) -> None:
    """A run of links, bodies and joints: its status, steps (the time they took as the progress's
    last line gives it: report["seconds"]) and energy balance, and the first outputs' start, end
    and range."""
    out.print(
        f"[bold]{shown(report['name'])}[/bold]: {report['status']} at t = {report['time_reached']:g} s, "
        f"{report['steps']} steps in {seconds_text(report['seconds'])} ({report.get('kernels') or 'interpreted'}); "
        f"energy balance error {balance_text(report['energy_balance_error'])}"
    )
    if report["message"]:
        out.print(shown(report["message"]))
    if report.get("accuracy"):
        print_accuracy(out, report["accuracy"])
    units = report.get("output_units", {})
    table = table_of(None, "output", "start", "end", "min", "max", text=1)
    outputs = list(report["outputs"].items())
    for name, values in outputs[:SHOWN_OUTPUTS]:
        if values:
            table.add_row(
                shown(name), *row_texts([values[0], values[-1], min(values), max(values)], units.get(name, ""))
            )
    out.print(table)
    print_left_out(out, min(SHOWN_OUTPUTS, len(outputs)), len(outputs), "outputs")


def print_accuracy(out: Console, accuracy: dict[str, Any]) -> None:
    """The discretization an accuracy target chose, and each output's estimated error."""
    steps = f"step {accuracy['step']:g} s" if "step" in accuracy else f"tolerance {accuracy['tolerance']:.3g}"
    elements = ", ".join(f"{shown(name)} {n}" for name, n in accuracy["intervals"].items()) or "no link elements"
    out.print(
        f"accuracy target {accuracy['target']:g} {'met' if accuracy['met'] else 'not met'}: elements {elements}; "
        f"{steps}; {len(accuracy['runs'])} runs in {seconds_text(accuracy['seconds'])}"
    )
    table = table_of(None, "output", "estimated error", "elements' part", "steps' part", text=1)
    for name, estimate in accuracy["estimated_errors"].items():
        table.add_row(
            shown(name),
            f"{estimate:.2g}",
            f"{accuracy['space_errors'][name]:.2g}",
            f"{accuracy['time_errors'][name]:.2g}",
        )
    out.print(table)


def print_impacts(out: Console, report: dict[str, Any], scheme: str) -> None:
    """A run of rigid bodies with impacts: its status, steps and energy balance, the first
    impacts and the end state's sensitivities."""
    out.print(
        f"[bold]{shown(report['name'])}[/bold]: {report['status']} at t = {report['time_reached']:g} s, "
        f"{report['steps']} steps ({scheme}) in {seconds_text(report['seconds'])}; energy balance error "
        f"{balance_text(report['energy_balance_error'])}"
    )
    units = report.get("event_units", {})

    def head(text: str, key: str) -> str:
        return f"{text} ({units[key]})" if units.get(key) else text

    table = table_of(
        None,
        "impact",
        "pair",
        "time (s)",
        head("impact speed", "impact_speed"),
        head("exit speed", "exit_speed"),
        "rebound (exit/impact)",
        text=2,
    )
    impacts = report["impacts"]
    for k, hit in enumerate(impacts[:SHOWN_IMPACTS]):
        table.add_row(
            str(k + 1),
            shown(hit["pair"]),
            f"{hit['time']:.7f}",
            hit["impact_speed"],
            hit["exit_speed"],
            hit["rebound_ratio"],
        )
    out.print(table)
    print_left_out(out, min(SHOWN_IMPACTS, len(impacts)), len(impacts), "impacts")
    if "sensitivities" in report:
        print_sensitivities(out, report["sensitivities"])


def print_sensitivities(out: Console, sensitivities: dict[str, Any]) -> None:
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
        row = [values["coordinates"][name] for name in names]
        table.add_row(shown(pointer), shown(values["unit"]), *row)
    out.print(table)
    for warning in sensitivities["warnings"]:
        out.print(f"[yellow]warning:[/yellow] {shown(warning)}")


def write_files(
    progress: SimulationProgress,
    files: Files,
    report: dict[str, Any],
    mech: Mechanism | None = None,
    history: History | None = None,
) -> None:
    """The files asked for, each announced as a part of the run: the report (--json), its
    histories (--csv), and the figures (links: of the report and of the raw history `history`;
    impacts: --plot alone)."""
    if files.json is not None:
        progress.stage(f"writing {files.json}")
        write_json(files.json, report)
    if files.csv is not None:
        from flexmech.api.cli.csv_files import history_columns, write_csv

        progress.stage(f"writing {files.csv}")
        write_csv(files.csv, history_columns(report))
    if files.plot is not None:
        progress.stage(f"drawing {files.plot}")
        if history is None:
            from flexmech.service.impacts.figures import plot_impacts

            _draw(plot_impacts, report, files.plot, option="--plot")
        else:
            from flexmech.service.dynamics.figures import plot_history

            _draw(plot_history, report, list(report["outputs"])[:PLOTTED_OUTPUTS], files.plot, option="--plot")
    if files.snapshots is not None:
        from flexmech.service.dynamics.figures import draw_snapshots

        progress.stage(f"drawing {files.snapshots}")
        _draw(draw_snapshots, mech, history, files.snapshots, option="--snapshots")
    if files.animation is not None:
        from flexmech.service.dynamics.figures import animate

        progress.stage(f"drawing {files.animation}")
        _draw(animate, mech, history, files.animation, option="--animation")


def _draw(draw: Callable[..., object], *args: Any, option: str) -> None:
    try:
        draw(*args)
    except OSError as exc:
        raise OptionError(option, f"cannot write {args[-1]}: {exc.strerror}") from None
