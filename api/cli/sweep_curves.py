"""The curves of a `flexmech sweep`: one model's sweep run and printed (a table of a few points,
the secant stiffness of a prescribed displacement, the target), each under a progress bar.
Imported when the command runs."""

from __future__ import annotations

from rich.console import Console
from rich.table import Table

from flexmech.api.cli.common import number, print_left_out, shown, spread, table_of
from flexmech.api.cli.sweep_plan import SweepPlan
from flexmech.models import Mechanism
from flexmech.models.elements import FAMILIES
from flexmech.service.drawings.figures import field_label, output_unit
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.sweep import SweepResult, TargetResult

SI_UNITS = {"force": "N", "moment": "N*m", "length": "m", "angle": "rad"}

# Points of each curve printed (the --json file has every one).
SHOWN_POINTS = 6


# --- the curves ------------------------------------------------------------------------------
def curve_label(mech: Mechanism, model: str | None) -> str:
    """The material (when there is one) and the model of the curved beams."""
    elements = mech.structure.elements
    materials = sorted({t.material for t in elements if hasattr(t, "material")})
    named = [getattr(FAMILIES.named(element.type), "model_name", None) for element in mech.document.elements.values()]
    models = sorted({name(element) for name, element in zip(named, mech.document.elements.values()) if name})
    parts = [", ".join(materials)] if len(materials) == 1 else []
    if model or models:  # a mechanism without curved beams has no model to name
        parts.append(model or (models[0] if len(models) == 1 else "mixed models"))
    return ", ".join(parts) or "curve"


def sweep_table(mech: Mechanism, label: str, result: SweepResult, x_output: str, y_output: str) -> Table:
    n = len(result.values)
    rows = spread(n, SHOWN_POINTS)
    unit = mech.doc_unit(mech.parameter_kind(result.path))
    converged = sum(s == "converged" for s in result.status)
    table = table_of(
        f"{label}: {n} points, {converged} converged, {result.seconds:.3g} s",
        "point",
        f"{field_label(result.path)} [{unit}]",
        f"{x_output} [{output_unit(mech, x_output)}]",
        f"{y_output} [{output_unit(mech, y_output)}]",
        "status",
        "iterations",
    )
    table.columns[0].justify = "right"
    table.columns[4].justify = "left"
    table.columns[4].overflow = "ellipsis"
    for i in rows:
        table.add_row(
            str(i),
            result.values[i],
            result.outputs[x_output][i],
            result.outputs[y_output][i],
            result.status[i],
            str(result.iterations[i]),
        )
    return table


def target_dict(target: TargetResult, plan: SweepPlan) -> dict:
    return {
        "goal": plan.goal,
        "status": target.status,
        "value": target.value,
        "unit": plan.unit,
        "iterations": target.equilibrium.iterations,
        "message": target.equilibrium.message,
    }


def print_unconverged_points(out: Console, label: str, result: SweepResult, plan: SweepPlan) -> None:
    """How many points did not converge, and the first of them."""
    bad = [i for i, s in enumerate(result.status) if s != "converged"]
    first = bad[0]
    residuals = result.residuals(first)
    out.print(
        f"[red]{label}: {len(bad)} of {len(result.status)} points did not converge[/red] "
        f"(first: point {first}, {plan.spec.path} = {number(result.values[first], plan.unit)}, "
        f"status {result.status[first]}, residual "
        f"{number(residuals['residual_norm'], residuals['residual_unit'])}, "
        f"{result.iterations[first]} iterations)"
    )


# --- the stiffness of a prescribed displacement --------------------------------------------
def stiffness_record(result: SweepResult, y_output: str) -> dict | None:
    """The secant stiffness of the reaction `y_output` against the prescribed displacement the
    sweep moves (document units: the reaction's unit per the field's), from the first point to
    the second ("first_step") and to the last ("last"); and at the start ("start"), the secant
    over a hundredth of the first step, solved from the first point's state (None if that
    solve fails). None when the first, second or last point did not converge."""
    from flexmech.service.solvers.equilibrium import solve_equilibrium

    mech, values, force = result.mechanism, result.values, result.outputs[y_output]
    if len(values) < 2 or values[1] == values[0] or any(result.status[i] != "converged" for i in (0, 1, -1)):
        return None
    small = (values[1] - values[0]) / 100
    near = solve_equilibrium(mech.with_values({result.path: float(values[0] + small)}), guess=result.z[0])
    y_kind = mech.graphs.output_kinds[mech.graphs.output_names.index(y_output)]
    x_kind = mech.parameter_kind(result.path)
    return {
        "output": y_output,
        "unit": f"{output_unit(mech, y_output)}/{mech.doc_unit(x_kind)}",
        "si_unit": f"{SI_UNITS[y_kind]}/{SI_UNITS[x_kind]}",
        "si_per_unit": mech.doc_factor(y_kind) / mech.doc_factor(x_kind),
        "first_step": float((force[1] - force[0]) / (values[1] - values[0])),
        "at_first_step": float(values[1]),
        "last": float((force[-1] - force[0]) / (values[-1] - values[0])),
        "at_last": float(values[-1]),
        "start": float((near.outputs()[y_output] - force[0]) / small) if near.converged else None,
        "start_step": float(small),
    }


def si_number(value: float) -> str:
    """3.25729e4, as a paper writes it."""
    mantissa, exponent = f"{value:.5e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def print_stiffness(out: Console, label: str, record: dict, plan: SweepPlan) -> None:
    """The secant stiffness at the first step and at the last, and the stiffness at the start,
    in document units and SI."""

    def both(k: float) -> str:
        return f"[bold]{shown(number(k, record['unit']))}[/bold] ({si_number(k * record['si_per_unit'])} {record['si_unit']})"

    first, last, start = record["first_step"], record["last"], record["start"]
    out.print(
        f"{shown(label)}: secant stiffness {shown(record['output'])} / {shown(field_label(plan.spec.path))}: "
        f"{both(first)} at the first step, {both(last)} at the last ({100 * (last / first - 1):+.2f} %)"
    )
    if start is not None:
        out.print(
            f"{shown(label)}: stiffness at the start {both(start)} (secant over "
            f"{number(record['start_step'], plan.unit)}); the last secant (at "
            f"{number(record['at_last'], plan.unit)}) is {100 * (last / start - 1):+.2f} % relative to it"
        )


def run_curve(
    out: Console, mech: Mechanism, model: str | None, plan: SweepPlan, options: NewtonOptions, advance
) -> tuple[tuple[str, SweepResult] | None, dict, bool]:
    """One model's sweep, printed: (the curve to plot or None, its JSON record, whether it failed)."""
    from flexmech.service.solvers.sweep import run_sweep_spec

    label = curve_label(mech, model)
    result, target = run_sweep_spec(mech, plan.spec, options, plan.restart, advance)
    if result is None:  # the end of the path (a target output value) was not reached
        eq = target.equilibrium
        out.print(
            f"{label}: target {plan.goal} not reached: status "
            f"[bold red]{target.status}[/bold red] after {eq.iterations} iterations, "
            f"residual {number(eq.residual_norm_force, mech.doc_unit('force'))}; "
            f"{shown(eq.message or 'no message')}"
        )
        return None, {"label": label, "model": model, "target": target_dict(target, plan)}, True
    record = {
        "label": label,
        "model": model,
        "sweep": result.to_dict(),
        "target": target_dict(target, plan) if target else None,
    }
    out.print(sweep_table(mech, label, result, plan.x_output, plan.y_output))
    print_left_out(out, len(spread(len(result.values), SHOWN_POINTS)), len(result.values), "points", spread_out=True)
    if plan.stiffness and (stiffness := stiffness_record(result, plan.y_output)) is not None:
        record["stiffness"] = stiffness
        print_stiffness(out, label, stiffness, plan)
    if target is not None:
        out.print(
            f"{label}: {plan.goal} at {field_label(plan.spec.path)} = [bold]{number(target.value, plan.unit)}[/bold]"
        )
    if not result.all_converged:
        print_unconverged_points(out, label, result, plan)
    return (label, result), record, not result.all_converged


def run_curves(
    out: Console,
    err: Console,
    mechs: list[Mechanism],
    models: list[str | None],
    plan: SweepPlan,
    options: NewtonOptions,
) -> tuple[list, list[dict], bool]:
    """Every model's sweep under a progress bar on stderr: (curves, records, whether any failed)."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    curves, records, failed = [], [], False
    with Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=err,
        transient=True,
        disable=not err.is_terminal,
    ) as progress:
        for mech, model in zip(mechs, models):
            task = progress.add_task(curve_label(mech, model), total=None)

            def advance(done: int, total: int, task=task) -> None:
                progress.update(task, completed=done, total=total)

            curve, record, curve_failed = run_curve(out, mech, model, plan, options, advance)
            progress.update(task, visible=False)
            curves += [curve] if curve is not None else []
            records.append(record)
            failed = failed or curve_failed
    return curves, records, failed
