"""`flexmech optimize`: the design problem of the document's `optimize` section."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console

from flexmech.api.cli.application import app
from flexmech.api.cli.common import EXIT_NOT_CONVERGED, consoles, number, shown, table_of, user_errors, write_json
from flexmech.api.cli.options import DocArg, JsonOpt, SetOpt, mechanism

if TYPE_CHECKING:  # the optimizer is imported when the command runs
    from flexmech.service.design.optimize import OptimizationResult, Prepared, StartResult
    from flexmech.service.design.problem import DesignProblem


def run_starts(err: Console, prepared: Prepared, starts: int) -> OptimizationResult:
    """Every start, one after the other, each reported on stderr when there are several."""
    from flexmech.service.design.optimize import combine, run_start

    runs = []
    for k in range(starts):
        runs.append(run_start(prepared, k))
        if starts > 1:
            err.print(f"start {k + 1}/{starts}: {runs[-1].status}, objective {runs[-1].objective:.6g}")
    return combine(prepared.problem, runs, sum(r.seconds for r in runs))


def print_optimum(out: Console, problem: DesignProblem, best: StartResult) -> None:
    """The objective, the design against its bounds and the constraints at the optimum."""
    mech = problem.mechanism
    out.print(
        f"objective {problem.spec.objective.output}: "
        f"{number(best.objective, mech.doc_unit(problem.objective.kind))}  "
        f"({best.iterations} IPOPT iterations, {best.seconds:.3g} s, equilibrium residual "
        f"{best.equilibrium_residual:.2g})"
    )
    table = table_of("design", "field", "start", "optimum", "lower", "upper", "multiplier")
    for k, path in enumerate(problem.paths):
        unit = mech.doc_unit(mech.parameter_kind(path))
        table.add_row(
            shown(path),
            number(best.design_start[path], unit),
            number(best.design[path], unit),
            number(problem.lower[k]),
            number(problem.upper[k]),
            number(best.multipliers["design"][k]),
        )
    out.print(table)
    if best.constraints:
        table = table_of("constraints", "output", "case", "value", "lower", "upper", "active", "multiplier")
        for row in best.constraints:
            table.add_row(
                shown(row["output"]),
                shown(row["case"]),
                number(row["value"]),
                "-" if row["lower"] is None else number(row["lower"]),
                "-" if row["upper"] is None else number(row["upper"]),
                "yes" if row["active"] else "no",
                number(row["multiplier"]),
            )
        out.print(table)


def print_sensitivities(out: Console, prepared: Prepared, best: StartResult, fields: list[str]) -> dict:
    """d(optimum)/d(field) for the given numeric fields; returns them as the report's entry."""
    from flexmech.service.design.sensitivity import optimum_sensitivities

    sens = optimum_sensitivities(prepared, best, fields)
    table = table_of("sensitivities of the optimum", "of", *fields)
    for name, row, row_units in zip(sens.outputs, sens.matrix, sens.units):
        table.add_row(shown(name), *(number(v, u) for v, u in zip(row, row_units)))
    out.print(table)
    return sens.to_dict()


@app.command()
def optimize(
    document: DocArg,
    sets: SetOpt = None,
    starts: Annotated[
        int | None, typer.Option(min=1, max=64, help="Number of starts (default: the document's).")
    ] = None,
    sensitivity: Annotated[
        list[str] | None,
        typer.Option(
            "--sensitivity", metavar="PATH", help="Also give d(optimum)/d(field) for this numeric field (repeatable)."
        ),
    ] = None,
    json_out: JsonOpt = None,
) -> None:
    """Solve the design problem of the document's `optimize` section: one NLP over the design
    variables and the equilibrium of every load case (IPOPT, exact derivatives)."""
    from flexmech.models import MechanismError
    from flexmech.service.design.optimize import prepare
    from flexmech.service.design.problem import design_problem

    out, err = consoles()
    with user_errors(err):
        mech = mechanism(document, None, sets)
        spec = mech.document.optimize
        if spec is None:
            raise MechanismError("/optimize", "the document has no optimize section (design, objective, constraints)")
        if starts is not None:
            spec = spec.model_copy(update={"starts": starts})
        problem = design_problem(mech, spec)
        prepared = prepare(problem)
        result = run_starts(err, prepared, spec.starts)
        best = result.best
        out.print(f"[bold]{shown(mech.document.name)}[/bold]  ({shown(str(document))}): optimize")
        out.print(f"status: {result.status}" + (f" ({shown(result.message)})" if result.message else ""))
        report = result.summary()
        if best is not None:
            print_optimum(out, problem, best)
            if sensitivity and best.succeeded:
                report["sensitivities"] = print_sensitivities(out, prepared, best, list(sensitivity))
        if json_out is not None:
            write_json(json_out, {"document": str(document), **report})
            out.print(f"wrote {shown(str(json_out))}")
    if result.status not in ("optimal", "acceptable"):
        raise typer.Exit(EXIT_NOT_CONVERGED)
