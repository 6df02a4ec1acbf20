"""`flexmech linearize`: the linear model of a mechanism for controllers, about its equilibrium
(or undeformed): the state space (A, B, C, D) from load components to outputs with M, damping and
K, written as .json, .npz or MATLAB .mat (service.vibration.state_space_files). It runs the
linearization analysis with its `state_space` option, as POST /v1/solve does."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.console import Console

from flexmech.api.cli.application import app
from flexmech.api.cli.common import (
    EXIT_NOT_CONVERGED,
    OptionError,
    consoles,
    shown,
    table_of,
    user_errors,
    write_json,
)
from flexmech.api.cli.options import DocArg, JsonOpt, ModelOpt, SetOpt, choice, mechanism

if TYPE_CHECKING:  # the models are imported when the command runs
    from flexmech.models import MechanismError

SUFFIXES = (".json", ".npz", ".mat")  # service.vibration.state_space_files.SUFFIXES (tests hold them equal)
SHOWN_MODES = 12
FLAGS = {"inputs": "--input", "outputs": "--output"}  # the options' fields named otherwise by a flag


StateSpaceOpt = Annotated[
    Path | None,
    typer.Option(
        "--state-space", metavar="OUT.json|npz|mat", help="Write the state space; its suffix names the format."
    ),
]
InputOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--input",
        metavar="POINTER",
        help="An input, one document unit: a load's component. Repeatable (default: every load component).",
    ),
]
OutputOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--output",
        metavar="NAME",
        help="An output, as in a solve's outputs. Repeatable (default: the document's named positions and "
        "rotations, else every body coordinate).",
    ),
]
AtOpt = Annotated[str, typer.Option(help="The state: equilibrium (under the document's loads) or undeformed.")]
ModesOpt = Annotated[int | None, typer.Option(help="Keep the lowest modes; D takes the rest's static response.")]


@app.command()
def linearize(
    document: DocArg,
    state_space: StateSpaceOpt = None,
    inputs: InputOpt = None,
    outputs: OutputOpt = None,
    at: AtOpt = "equilibrium",
    modes: ModesOpt = None,
    damping_ratio: Annotated[float, typer.Option(help="Modal damping ratio on every mode.")] = 0.0,
    mass_damping: Annotated[float, typer.Option(help="Rayleigh's alpha (damping = alpha M + beta K), in 1/s.")] = 0.0,
    stiffness_damping: Annotated[float, typer.Option(help="Rayleigh's beta, in s.")] = 0.0,
    model: ModelOpt = None,
    sets: SetOpt = None,
    json_out: JsonOpt = None,
) -> None:
    """The linear model about the equilibrium (or undeformed) for controllers: the state space over
    the modes (poles = the modes' frequencies, static gain = the static compliance), with M,
    damping and K; as JSON, .npz or MATLAB .mat, or from Python as a python-control StateSpace."""
    out, err = consoles()
    with user_errors(err):
        if state_space is not None and state_space.suffix.lower() not in SUFFIXES:
            raise OptionError(
                "--state-space",
                f"cannot tell the format of '{state_space}': use a name ending in {', '.join(SUFFIXES)}",
            )
        choice("--at", at, ("equilibrium", "undeformed"))
        asked = {
            "inputs": inputs or None,
            "outputs": outputs or None,
            "modes": modes,
            "damping_ratio": damping_ratio,
            "mass_damping": mass_damping,
            "stiffness_damping": stiffness_damping,
        }
        report = _run(mechanism(document, model, sets), at, asked)
        out.print(f"[bold]{shown(report['name'])}[/bold]  ({shown(str(document))}): linear model at {at}")
        _print_and_write(out, report, state_space)
        if json_out is not None:
            write_json(json_out, {"document": str(document), "model": model, **report})
            out.print(f"wrote {shown(str(json_out))}")
    if report.get("status") != "converged":
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _print_and_write(out: Console, report: dict[str, Any], path: Path | None) -> None:
    """The status and warnings, the state space's modes and static gain, and its file."""
    from flexmech.api.cli.report_tables import print_status  # it imports the models

    print_status(out, report)
    for note in report.get("warnings", []):
        out.print(f"[yellow]warning:[/yellow] {shown(note)}")
    if "state_space" not in report:
        return
    print_state_space(out, report["state_space"])
    if path is not None:
        from flexmech.service.vibration.state_space import StateSpaceModel
        from flexmech.service.vibration.state_space_files import write_state_space

        try:
            write_state_space(StateSpaceModel.from_dict(report["state_space"]), path)
        except OSError as exc:
            raise OptionError("--state-space", f"cannot write {path}: {exc.strerror}") from None
        out.print(f"wrote {shown(str(path))}")


def _run(mech: Any, at: str, asked: dict[str, Any]) -> dict[str, Any]:
    """The linearization analysis' report with its state space; a problem with an option named by its flag."""
    from flexmech.models import MechanismError
    from flexmech.service.analyses import ANALYSES, AnalysisRequest

    try:
        return ANALYSES.named("linearization").run(mech, AnalysisRequest(given={"at": at, "state_space": asked}))
    except MechanismError as exc:
        raise _flagged(exc, asked) from None


def _flagged(exc: MechanismError, asked: dict[str, Any]) -> Exception:
    """An error at /state_space/<field>[/k] as the flag's: --input '<pointer>': ..."""
    parts = exc.pointer.split("/")
    if len(parts) < 3 or parts[1] != "state_space":
        return exc
    field = parts[2]
    flag = FLAGS.get(field, "--" + field.replace("_", "-"))
    if len(parts) > 3 and parts[3].isdigit() and asked.get(field):
        value = asked[field][int(parts[3])]
        if value not in exc.problem:
            flag += f" '{value}'"
    return OptionError(flag, exc.problem)


def print_state_space(out: Console, space: dict[str, Any]) -> None:
    """Its size, the lowest modes' frequencies and damping ratios, and the static gain."""
    units = space["units"]
    if not space["states"]:
        out.print(
            f"state space: no states (the mechanism has no mass: the model is its static response D), "
            f"{len(space['inputs'])} inputs, {len(space['outputs'])} outputs"
        )
    else:
        _print_modes(out, space)
    gain = space["static_gain"]
    if gain is None:
        out.print("static gain: none (a rigid mode: no static equilibrium)")
        return
    from flexmech.service.display import displays
    from flexmech.service.drawings.figures import field_label

    cells = {(i, j): value for i, row in enumerate(gain) for j, value in enumerate(row)}
    cell_units = {(i, j): f"{units['outputs'][i]}/{units['inputs'][j]}" for i, j in cells}
    shown_as = displays(cells, cell_units)  # one display per unit (output per input)
    table = table_of(
        "static gain (output per input)",
        "output",
        *(field_label(pointer) for pointer in space["inputs"]),
    )
    for i, name in enumerate(space["outputs"]):
        table.add_row(shown(name), *(shown_as[(i, j)].text(v, with_unit=True) for j, v in enumerate(gain[i])))
    out.print(table)


def _print_modes(out: Console, space: dict[str, Any]) -> None:
    out.print(
        f"state space: {len(space['states'])} states (the modes' coordinates and rates), "
        f"{len(space['inputs'])} inputs, {len(space['outputs'])} outputs; time in s"
    )
    table = table_of("modes", "mode", "kind", "frequency (Hz)", "damping ratio (relative)", text=2)
    for k, (kind, f, zeta) in enumerate(zip(space["kinds"], space["frequencies"], space["damping_ratios"])):
        if k < SHOWN_MODES:
            table.add_row(str(k + 1), kind, f, zeta)
    out.print(table)
    if len(space["kinds"]) > SHOWN_MODES:
        out.print(f"... and {len(space['kinds']) - SHOWN_MODES} more modes (the file has them all)", style="dim")
