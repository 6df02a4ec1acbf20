"""`flexmech contact`: gripping contact. With a path (the document's contacts.path, or one
field given by --path), the quasi-static path state after state, each from the one before;
with --single (or no path), one state. Prints each pair's forces; --plot draws a result
against the path's field, --shapes chosen states (fingers, jaws, objects, forces)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flexmech.api.cli.application import app
from flexmech.api.cli.common import (
    EXIT_NOT_CONVERGED,
    OptionError,
    check_plot_option,
    consoles,
    number,
    print_left_out,
    shown,
    table_of,
    user_errors,
    write_json,
)
from flexmech.api.cli.options import DocArg, JsonOpt, PlotOpt, SetOpt, choice, mechanism
from flexmech.service.drawings.figures import field_label

SHOWN_STATES = 8

PathOpt = Annotated[
    str | None,
    typer.Option(
        "--path", metavar="POINTER", help="The field the path moves (instead of the document's contacts.path)."
    ),
]


@app.command()
def contact(
    document: DocArg,
    sets: SetOpt = None,
    path: PathOpt = None,
    start: Annotated[float | None, typer.Option(help="--path: first value (document units).")] = None,
    stop: Annotated[float | None, typer.Option(help="--path: last value.")] = None,
    steps: Annotated[int, typer.Option(help="--path: equal steps.")] = 50,
    single: Annotated[bool, typer.Option("--single", help="Solve the document's state only.")] = False,
    output: Annotated[
        str | None, typer.Option("--output", help="The result --plot draws (default: the first pair's force_x).")
    ] = None,
    shapes: Annotated[Path | None, typer.Option("--shapes", metavar="OUT.png|svg", help="Draw chosen states.")] = None,
    at: Annotated[
        str | None,
        typer.Option(
            "--at", metavar="I,J,...", help="--shapes: state indices (default: four spread over the contact)."
        ),
    ] = None,
    penetrating_start: Annotated[str, typer.Option(help="approach | refuse.")] = "approach",
    friction: Annotated[
        list[float] | None,
        typer.Option(
            "--friction",
            metavar="MU",
            help="Run the path with every pair's friction coefficient MU; "
            "repeat to compare runs (--plot draws one curve each).",
        ),
    ] = None,
    json_out: JsonOpt = None,
    plot: PlotOpt = None,
) -> None:
    """Contact of fingers (links by elements) with rigid objects: forces from the multipliers."""
    out, err = consoles()
    with user_errors(err):
        check_plot_option(plot)
        check_plot_option(shapes)
        choice("--penetrating-start", penetrating_start, ("approach", "refuse"))
        mech = mechanism(document, None, sets)
        from flexmech.models import MechanismError
        from flexmech.service.contact.problem import contact_problem
        from flexmech.service.contact.solve import ContactOptions

        try:
            problem = contact_problem(mech.structure)
        except MechanismError as exc:
            raise exc from None
        options = ContactOptions(penetrating_start)
        parameters = _path_parameters(mech, path, start, stop, steps)
        if single or parameters is None:
            ok = _single_state(out, mech, problem, options, json_out)
        else:
            ok = _path(out, mech, problem, options, parameters, output, json_out, plot, shapes, at, friction)
    if not ok:
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _path_parameters(mech, path, start, stop, steps) -> list[dict] | None:
    if path is not None:
        if start is None or stop is None:
            raise OptionError("--path", "needs --start and --stop")
        if steps < 1:
            raise OptionError("--steps", f"must be at least 1, got {steps}")
        return [{"path": path, "start": start, "stop": stop, "steps": steps}]
    for option, value in (("--start", start), ("--stop", stop)):
        if value is not None:
            raise OptionError(option, "needs --path (without it the document's contacts.path is run)")
    spec = mech.document.contacts.path if mech.document.contacts is not None else None
    return None if spec is None else [p.model_dump(exclude_none=True) for p in spec.parameters]


def _single_state(out, mech, problem, options, json_out) -> bool:
    from flexmech.models import MechanismError
    from flexmech.service.analyses.base import AnalysisRequest
    from flexmech.service.analyses.contact import CONTACT

    try:
        report = CONTACT.run(mech, AnalysisRequest(given={"penetrating_start": options.penetrating_start}))
    except MechanismError as exc:
        raise MechanismError(exc.pointer.removeprefix("/document"), exc.problem) from None
    out.print(
        f"[bold]{shown(mech.document.name)}[/bold]: {report['status']} in {report['iterations']} iterations, "
        f"{report['seconds'] * 1e3:.1f} ms"
    )
    f, length = report["units"]["force"], report["units"]["length"]
    table = table_of(
        None,
        "pair",
        "state",
        f"F_x [{f}]",
        f"F_y [{f}]",
        f"normal [{f}]",
        f"friction [{f}]",
        f"point x [{length}]",
        f"point y [{length}]",
        text=2,
    )
    for name, pair in report["pairs"].items():
        point = pair["point"] or [None, None]
        table.add_row(
            shown(name),
            pair["state"],
            pair["force"][0],
            pair["force"][1],
            pair["normal_force"],
            pair["friction_force"],
            point[0],
            point[1],
        )
    out.print(table)
    for note in report["warnings"]:
        out.print(f"[yellow]warning:[/yellow] {shown(note)}")
    if json_out is not None:
        write_json(json_out, report)
    return report["status"] == "converged"


def _runs(mech, friction: list[float] | None) -> list[tuple[str, object]]:
    """(label, mechanism) of each run: the document's, or one per --friction value."""
    import numpy as np

    if not friction:
        return [("", mech)]
    pairs = [pair.friction_pointer for pair in mech.structure.contacts.pairs]
    runs = []
    for mu in friction:
        if not np.isfinite(mu) or mu < 0:
            raise OptionError("--friction", f"must be a number of at least 0, got {mu:g}")
        runs.append((f"mu = {mu:g}", mech.with_values({pointer: mu for pointer in pairs})))
    return runs


def _path(out, mech, problem, options, parameters, output, json_out, plot, shapes, at, friction) -> bool:
    from flexmech.service.contact.path import default_outputs, path_fields

    fields = path_fields(mech, parameters, "--path")
    chosen = _chosen(at, fields.states)  # checked before the path is solved
    spec = mech.document.contacts.path
    wanted = list(spec.outputs) if spec is not None and spec.outputs else default_outputs(problem)
    for name in wanted:
        if name not in problem.output_names:
            raise OptionError("contacts.path.outputs", f"unknown output '{name}'")
    y_name = output or wanted[0]
    if y_name not in problem.output_names:
        raise OptionError("--output", f"unknown output '{y_name}' (outputs: {', '.join(wanted)}, and the mechanism's)")
    wanted = wanted + ([y_name] if y_name not in wanted else [])
    runs = []
    for label, run_mech in _runs(mech, friction):
        states, records = _follow(out, run_mech, problem, fields, options, wanted, label)
        _print_path(out, run_mech, fields, records, y_name, problem, label)
        runs.append((label, run_mech, states, records))
    if json_out is not None:
        points = [[{k: v for k, v in r.items() if k != "state"} for r in records] for *_, records in runs]
        write_json(
            json_out,
            {
                "document": mech.document.name,
                "parameters": [{"path": p, "values": list(v)} for p, v in zip(fields.pointers, fields.values)],
                **(
                    {"points": points[0]}
                    if not friction
                    else {"runs": [{"friction": mu, "points": p} for mu, p in zip(friction, points)]}
                ),
            },
        )
    if plot is not None:
        _plot_path(mech, problem, fields, [(label, records) for label, _, _, records in runs], y_name, plot)
    if shapes is not None:
        _, run_mech, states, _ = runs[-1]
        _plot_shapes(run_mech, problem, states, fields, chosen, shapes)
    return all(r["status"] == "converged" for *_, records in runs for r in records)


def _follow(out, mech, problem, fields, options, wanted, label):
    from rich.progress import Progress

    from flexmech.service.contact.path import follow, state_record

    states, records = [], []
    with Progress(transient=True, console=out) as progress:
        task = progress.add_task(f"contact path {label}".strip(), total=fields.states)
        for index, state in follow(mech, problem, fields, list(range(fields.states)), None, options):
            states.append(state)
            records.append(state_record(mech, problem, state, fields.at(index), wanted))
            progress.advance(task)
    return states, records


def _print_path(out, mech, fields, records, y_name, problem, label: str) -> None:
    import numpy as np

    unit = mech.doc_unit(mech.parameter_kind(fields.pointers[0]))
    y_unit = mech.doc_unit(problem.output_kinds[problem.output_names.index(y_name)])
    converged = [r for r in records if r["status"] == "converged"]
    seconds = sum(r["seconds"] for r in records)
    out.print(
        f"[bold]{shown(mech.document.name)}[/bold]{shown(', ' + label) if label else ''}: "
        f"{len(converged)} of {len(records)} states converged, "
        f"{seconds:.3f} s ({1e3 * seconds / max(len(records), 1):.1f} ms per state)"
    )
    table = table_of(None, f"{field_label(fields.pointers[0])} [{unit}]", "pairs", f"{y_name} [{y_unit}]", text=2)
    table.columns[0].justify = "right"
    step = max(1, len(records) // SHOWN_STATES)
    for r in records[::step]:
        states = ", ".join(f"{name} {pair['state']}" for name, pair in r["pairs"].items())
        table.add_row(r["values"][0], states, r["outputs"].get(y_name))
    out.print(table)
    print_left_out(out, len(records[::step]), len(records), "states", spread_out=True)
    values = np.array([r["outputs"][y_name] if r["status"] == "converged" else np.nan for r in records])
    if np.isfinite(values).any():
        k = int(np.nanargmax(np.abs(values)))
        out.print(
            f"largest |{shown(y_name)}| = {number(abs(values[k]), y_unit)} at {shown(field_label(fields.pointers[0]))} = "
            f"{number(records[k]['values'][0], unit)}"
        )
    failed = [r for r in records if r["status"] != "converged"]
    for r in failed[:3]:
        out.print(f"[yellow]not converged[/yellow] at {number(r['values'][0], unit)}: {shown(r['message'])}")
    print_left_out(out, min(3, len(failed)), len(failed), "states that did not converge")


def _plot_path(mech, problem, fields, runs, y_name, plot) -> None:
    import numpy as np

    from flexmech.service.contact.plots import plot_path

    unit = mech.doc_unit(mech.parameter_kind(fields.pointers[0]))
    y_unit = mech.doc_unit(problem.output_kinds[problem.output_names.index(y_name)])
    curves = []
    for label, records in runs:
        x = np.array([r["values"][0] for r in records])
        y = np.array([r["outputs"][y_name] if r["status"] == "converged" else np.nan for r in records])
        curves.append((label or y_name, x, y))
    try:
        plot_path(
            curves, f"{field_label(fields.pointers[0])} [{unit}]", f"{y_name} [{y_unit}]", mech.document.name, plot
        )
    except OSError as exc:
        raise OptionError("--plot", f"cannot write {plot}: {exc.strerror}") from None


def _chosen(at: str | None, states: int) -> list[int] | None:
    """The --at state indices (None: chosen after the path)."""
    if at is None:
        return None
    try:
        chosen = [int(item) for item in at.split(",") if item.strip()]
    except ValueError:
        raise OptionError("--at", f"expected state indices like 0,10,20, got '{at}'") from None
    bad = [i for i in chosen if not 0 <= i < states]
    if bad or not chosen:
        raise OptionError("--at", f"state {bad[0] if bad else at!r} is not on the path (0 to {states - 1})")
    return chosen


def _plot_shapes(mech, problem, states, fields, chosen, shapes) -> None:
    import numpy as np

    from flexmech.service.contact.plots import plot_states
    from flexmech.service.drawings.figures import field_label

    if chosen is None:
        touching = [i for i, s in enumerate(states) if s.converged and any(t != "open" for t in s.pair_states)]
        pool = touching or list(range(len(states)))
        chosen = sorted({pool[int(k)] for k in np.linspace(0, len(pool) - 1, min(4, len(pool)))})
    unit = mech.doc_unit(mech.parameter_kind(fields.pointers[0]))
    labels = [f"{field_label(fields.pointers[0])} = {fields.at(i)[0]:.4g} {unit}" for i in chosen]
    try:
        plot_states(mech, problem, [states[i] for i in chosen], labels, shapes)
    except OSError as exc:
        raise OptionError("--shapes", f"cannot write {shapes}: {exc.strerror}") from None
