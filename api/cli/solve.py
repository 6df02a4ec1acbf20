"""`flexmech solve`: one analysis of one mechanism, dispatched through the analyses registry
(service.analyses), so the --json file is the report POST /v1/solve answers plus the
command's own keys (document, model, overrides)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console

from flexmech.api.cli.application import app
from flexmech.api.cli.catalog import analysis_names
from flexmech.api.cli.common import (
    EXIT_NOT_CONVERGED,
    OptionError,
    check_plot_option,
    consoles,
    number,
    save_plot,
    shown,
    table_of,
    user_errors,
    write_json,
)
from flexmech.api.cli.options import (
    DocArg,
    JacobianOpt,
    JsonOpt,
    LineSearchOpt,
    MaxIterOpt,
    ModelOpt,
    PlotOpt,
    SetOpt,
    mechanism,
    newton_options,
    overrides,
)
from flexmech.api.cli.problems import every_problem, in_the_file
from flexmech.service.drawings.figures import field_label

if TYPE_CHECKING:  # the analyses and solvers are imported when the command runs
    from flexmech.models import Mechanism
    from flexmech.service.analyses import Analysis
    from flexmech.service.solvers.equilibrium import EquilibriumResult
    from flexmech.service.solvers.newton import NewtonOptions

# The analyses whose report is a solution (an EquilibriumResult): the CLI calls their solver
# itself, for the result that --plot draws, and builds the same report the registry does.
SOLVERS = ("equilibrium", "energy")
FINE = ("converged", "finished")  # a solve's, a run's status that is a result (exit 0)


def solver_of(name: str):
    """The solver of an analysis of SOLVERS: (mech, options) -> EquilibriumResult."""
    from flexmech.service.solvers.energy import minimize_energy
    from flexmech.service.solvers.equilibrium import solve_equilibrium

    return {"equilibrium": solve_equilibrium, "energy": minimize_energy}[name]


def analysis_named(name: str) -> Analysis:
    from flexmech.models import MechanismError
    from flexmech.service.analyses import ANALYSES

    try:
        return ANALYSES.named(name)
    except MechanismError as exc:
        raise OptionError("--analysis", exc.problem) from None


def run_analysis(
    mech: Mechanism, analysis: Analysis, options: NewtonOptions, stiffness: bool
) -> tuple[EquilibriumResult | None, dict]:
    """(the solution, or None for an analysis that has none; the analysis' report)."""
    from flexmech.models import MechanismError
    from flexmech.service.analyses import AnalysisRequest
    from flexmech.service.analyses.equilibrium import solution_report
    from flexmech.service.solvers.reports import stiffness_dict

    if analysis.name not in SOLVERS:
        try:
            asked = {"stiffness": stiffness} if "stiffness" in analysis.Options.model_fields else {}
            return None, analysis.run(mech, AnalysisRequest(options, asked))
        except MechanismError as exc:
            raise every_problem(in_the_file(exc)) from None
    result = solver_of(analysis.name)(mech, options)
    report = solution_report(mech, result, analysis.name)
    if stiffness and result.converged:
        report["stiffness"] = stiffness_dict(mech, result.z)
    return result, report


def print_report(out: Console, mech: Mechanism, report: dict, stiffness: bool) -> None:
    from flexmech.api.cli.report_tables import print_solution, print_status, print_stiffness, print_wrenches

    if report["analysis"] not in SOLVERS and "limit_points" not in report and "wrenches" not in report:
        from flexmech.api.cli.analysis_commands import print_report as print_analysis
        from flexmech.api.cli.simulate_output import print_impacts, print_run

        if report["analysis"] == "simulate" and "impacts" in report:  # as flexmech simulate prints it
            print_impacts(out, report, report["scheme"]["name"])
        elif report["analysis"] == "simulate":
            print_run(out, report)
        else:
            print_analysis(out, report)  # as its own command prints it (flexmech modes ...)
        if stiffness and "stiffness" not in report and report["status"] in FINE:
            out.print(f"[yellow]warning:[/yellow] --stiffness: the {report['analysis']} analysis reports no stiffness")
        return
    print_status(out, report)
    if report["analysis"] in SOLVERS:
        if report["status"] == "converged":
            print_solution(out, mech, report)
            for note in report["warnings"]:
                out.print(f"[yellow]warning:[/yellow] {shown(note)}")
        else:
            out.print("[yellow]no equilibrium found: the last iterate is not reported as a solution[/yellow]")
    if "limit_points" in report:
        print_path_summary(out, report)
    if "wrenches" in report:
        print_wrenches(out, report)
    if "stiffness" in report:
        print_stiffness(out, report["stiffness"])
    elif stiffness and report["status"] == "converged":
        out.print(f"[yellow]warning:[/yellow] --stiffness: the {report['analysis']} analysis reports no stiffness")


def print_path_summary(out: Console, report: dict) -> None:
    """A trace's extent and its limit points (`flexmech trace` tables the path; the --json file
    has every point)."""
    values, unit, limits = report["values"], report["unit"], report["limit_points"]
    if values:
        out.print(
            f"path of {shown(report['path'])} (from the {report['source']}): {len(values)} points from "
            f"{number(values[0], unit)} to {number(values[-1], unit)}, {len(limits)} limit points"
        )
    if limits:
        table = table_of("limit points", "kind", f"{field_label(report['path'])} [{unit}]", "after point")
        for lp in limits:
            table.add_row(lp["kind"], lp["value"], str(lp["after_point"]))
        out.print(table)


def check_solve_options(analysis: Analysis, plot: Path | None) -> None:
    check_plot_option(plot)
    if plot is not None and analysis.name not in SOLVERS:
        raise OptionError(
            "--plot", f"draws a solution: use it with --analysis {' or '.join(SOLVERS)}, not {analysis.name}"
        )


@app.command()
def solve(
    document: DocArg,
    analysis: Annotated[
        str, typer.Option("--analysis", help=f"The analysis: {' | '.join(analysis_names())}.")
    ] = "equilibrium",
    model: ModelOpt = None,
    sets: SetOpt = None,
    jacobian: JacobianOpt = "full",
    line_search: LineSearchOpt = True,
    max_iterations: MaxIterOpt = 50,
    json_out: JsonOpt = None,
    plot: PlotOpt = None,
    stiffness: Annotated[
        bool,
        typer.Option(
            "--stiffness",
            help="Print the tangent stiffness K_T at the solution, and its terms I, II, III (Cammarata et al. 2022) and load term where they apply.",
        ),
    ] = False,
) -> None:
    """Solve the equilibrium of a mechanism under its loads (or another analysis of it)."""
    out, err = consoles()
    with user_errors(err):
        chosen = analysis_named(analysis)
        check_solve_options(chosen, plot)
        options = newton_options(jacobian, line_search, max_iterations)
        mech = mechanism(document, model, sets)
        result, report = run_analysis(mech, chosen, options, stiffness)

        out.print(f"[bold]{shown(mech.document.name)}[/bold]  ({shown(str(document))})")
        for pointer in overrides(sets):
            out.print(f"  {pointer} = {number(mech.value(pointer), mech.doc_unit(mech.parameter_kind(pointer)))}")
        print_report(out, mech, report, stiffness)
        if json_out is not None:
            write_json(json_out, {"document": str(document), "model": model, "overrides": overrides(sets), **report})
            out.print(f"wrote {shown(str(json_out))}")
        if plot is not None:
            from flexmech.service.drawings.plotting import plot_configuration

            save_plot(plot_configuration, result, plot)
            out.print(f"wrote {shown(str(plot))}")
    if report["status"] not in FINE:
        raise typer.Exit(EXIT_NOT_CONVERGED)
