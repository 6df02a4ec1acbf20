"""`flexmech optimize`: the design problem of the document's `optimize` section."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console

from flexmech.api.cli.application import app
from flexmech.api.cli.common import EXIT_NOT_CONVERGED, consoles, number, shown, table_of, user_errors, write_json
from flexmech.api.cli.options import DocArg, JsonOpt, SetOpt, mechanism
from flexmech.api.cli.quantities import exact_text, row_texts

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
    """The objective, the design against its bounds and the constraints at the optimum; each
    row's numbers in one display of its quantity (round-off below the model's scale as 0), a
    multiplier in objective unit per unit, those of inactive bounds (IPOPT's 1e-13) as 0."""
    mech = problem.mechanism
    objective_unit = _unit(problem, problem.objective)
    out.print(
        f"objective {shown(_label(problem.spec.objective.output, problem.objective))}: "
        f"{shown(number(best.objective, objective_unit, reference=_scale(problem, problem.objective)))}  "
        f"({best.iterations} IPOPT iterations, {best.seconds:.3g} s, equilibrium residual "
        f"{exact_text(best.equilibrium_residual)} (nondimensional))"
    )
    table = table_of("design", "field", "start", "optimum", "lower", "upper", "multiplier")
    kinds = [mech.parameter_kind(path) for path in problem.paths]
    multipliers = _multiplier_texts(
        best.multipliers["design"],
        [_per(objective_unit, mech.doc_unit(kind)) for kind in kinds],
        [mech.nd_per_doc(kind) * _scale(problem, problem.objective) for kind in kinds],
    )
    for k, path in enumerate(problem.paths):
        values = [best.design_start[path], best.design[path], problem.lower[k], problem.upper[k]]
        table.add_row(shown(path), *row_texts(values, mech.doc_unit(kinds[k])), shown(multipliers[k]))
    out.print(table)
    if best.constraints:
        refs = [c.output for c in problem.constraints]
        multipliers = _multiplier_texts(
            [row["multiplier"] / _shown_per(ref) for row, ref in zip(best.constraints, refs)],
            [_per(objective_unit, _unit(problem, ref)) for ref in refs],
            [_scale(problem, problem.objective) / (_scale(problem, ref) * _shown_per(ref) or 1.0) for ref in refs],
        )
        table = table_of("constraints", "output", "case", "value", "lower", "upper", "active", "multiplier")
        for row, ref, multiplier in zip(best.constraints, refs, multipliers):
            per = _shown_per(ref)
            value, lower, upper = row_texts(
                [None if row[k] is None else row[k] * per for k in ("value", "lower", "upper")],
                _unit(problem, ref),
                reference=_scale(problem, ref) * per,
            )
            table.add_row(
                shown(_label(row["output"], ref)),
                shown(row["case"]),
                shown(value),
                "-" if row["lower"] is None else shown(lower),
                "-" if row["upper"] is None else shown(upper),
                "yes" if row["active"] else "no",
                shown(multiplier),
            )
        out.print(table)


def print_robust(out: Console, entries: list[dict]) -> None:
    """The robust objective and constraints at the optimum (first order over the tolerances):
    each output's nominal value, sigma and mean -+ k sigma, and each yield with its specs' shares."""
    sigmas = [e for e in entries if "sigma" in e]
    if sigmas:
        table = table_of(
            "robust (first order)",
            "of",
            "output",
            "case",
            "nominal",
            "sigma",
            "k (sigmas)",
            "mean - k sigma",
            "mean + k sigma",
        )
        for e in sigmas:
            values = row_texts([e["nominal"], e["sigma"], e["mean_minus_k_sigma"], e["mean_plus_k_sigma"]], e["unit"])
            table.add_row(
                shown(e["of"]), shown(e["output"]), shown(e["case"]), *values[:2], f"{e['sigmas']:g}", *values[2:]
            )
        out.print(table)
    for e in (e for e in entries if e["output"] == "yield"):
        table = table_of(
            f"{e['of']}: yield {100 * e['yield']:.4g} % (first order, {e['case']})",
            "spec",
            "nominal",
            "sigma",
            "min",
            "max",
            "share (%)",
        )
        for name, spec in e["specs"].items():
            nominal, sigma, low, high = row_texts(
                [spec["nominal"], spec["sigma"], spec["min"], spec["max"]], spec["unit"]
            )
            table.add_row(
                shown(name),
                nominal,
                sigma,
                "-" if spec["min"] is None else low,
                "-" if spec["max"] is None else high,
                f"{100 * spec['share']:.4g}",
            )
        out.print(table)


def _shown_per(ref) -> float:
    """Shown units per document unit: a yield (a share of one) in %."""
    return 100.0 if ref.source == "yield" else 1.0


def _label(name: str, ref) -> str:
    """An output as the problem holds it: a robust one's mean + k sigma or mean - k sigma."""
    return f"{name} {'+' if ref.sigmas > 0 else '-'} {abs(ref.sigmas):g} sigma" if ref.sigmas else name


def _scale(problem: DesignProblem, ref) -> float:
    """One nondimensional unit of a design output, in its document unit (0 for a response)."""
    return 0.0 if ref.source == "response" else 1.0 / problem.mechanism.nd_per_doc(ref.kind)


def _multiplier_texts(values: list[float], units: list[str], references: list[float]) -> list[str]:
    """Multipliers with their units, each below NOISE of the largest of its unit (or of its
    scale, objective scale per the bound's) as 0."""
    from flexmech.service.display import display

    by_unit: dict[str, list[float]] = {}
    for value, unit in zip(values, units):
        by_unit.setdefault(unit, []).append(value)
    texts = []
    for value, unit, reference in zip(values, units, references):
        shown = display(unit, by_unit[unit], "ratio", reference)
        texts.append(shown.text(value, with_unit=True))
    return texts


def _unit(problem: DesignProblem, ref) -> str:
    """The document unit of a design output (a response's own unit; a yield in %)."""
    if ref.source == "yield":
        return "%"
    return ref.unit if ref.source == "response" else problem.mechanism.doc_unit(ref.kind)


def _per(numerator: str, denominator: str) -> str:
    if not denominator:
        return numerator
    return (
        f"{numerator or '1'}/({denominator})"
        if "*" in denominator or "/" in denominator
        else f"{numerator or '1'}/{denominator}"
    )


def print_sensitivities(out: Console, prepared: Prepared, best: StartResult, fields: list[str]) -> dict:
    """d(optimum)/d(field) for the given numeric fields; returns them as the report's entry."""
    from flexmech.service.design.sensitivity import optimum_sensitivities

    sens = optimum_sensitivities(prepared, best, fields)
    table = table_of("sensitivities of the optimum", "of", *fields)
    for name, row, row_units in zip(sens.outputs, sens.matrix, sens.units):
        table.add_row(shown(name), *(shown(number(v, u)) for v, u in zip(row, row_units)))
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
            print_robust(out, report.get("robust", []))
            if sensitivity and best.succeeded:
                report["sensitivities"] = print_sensitivities(out, prepared, best, list(sensitivity))
        if json_out is not None:
            write_json(json_out, {"document": str(document), **report})
            out.print(f"wrote {shown(str(json_out))}")
    if result.status not in ("optimal", "acceptable"):
        raise typer.Exit(EXIT_NOT_CONVERGED)
