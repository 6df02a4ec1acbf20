"""The flexmech command line: solve a mechanism document, sweep a load, list the examples.

    flexmech solve examples/gripper.json --set /loads/actuation/force/1=77 --stiffness
    flexmech sweep examples/gripper.json --compare-models --plot sweep.png
    flexmech optimize examples/grasper_shape.json
    flexmech trace examples/snap_through_arch.json --path /loads/P/force/1 --stop -300 --step 20
    flexmech examples

Exit codes: 0 success; 1 the solver did not converge (status and diagnostics are printed,
and --json/--plot files are still written); 2 a problem with the document or the options,
printed as one line "error: <where>: <problem>" on stderr.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from models import Mechanism, MechanismError, compile_mechanism, load_document
from models import MODELS
from models.units import quantity_to_si
from service.analysis import plain
from service.equilibrium import EquilibriumResult, NewtonOptions, solve_equilibrium
from service.examples import examples_directory
from service.plotting import PLOT_SUFFIXES, field_label, output_unit
from service.stiffness import TangentStiffness, tangent_stiffness

app = typer.Typer(
    name="flexmech",
    help="Kinetostatics of planar compliant mechanisms described by a mechanism document.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_show_locals=False,
)

JACOBIANS = ("full", "first_term", "frozen")
RESTARTS = ("previous", "undeformed")
EXIT_NOT_CONVERGED = 1
EXIT_ERROR = 2
_FILE_WIDTH = 160


class OptionError(Exception):
    """A command-line option that cannot be used; `where` names the option."""

    def __init__(self, where: str, problem: str):
        self.where = where
        self.problem = problem
        super().__init__(f"{where}: {problem}")


# --- shared options ------------------------------------------------------------------------
DocArg = Annotated[Path, typer.Argument(help="Mechanism document (JSON or YAML).", show_default=False)]
ModelOpt = Annotated[str | None, typer.Option(
    "--model", help=f"Model of every curved beam: {' | '.join(MODELS)} (default: as in the document).")]
SetOpt = Annotated[list[str] | None, typer.Option(
    "--set", metavar="POINTER=VALUE",
    help='Override a numeric field, in document units or as a quantity ("5 um"). Repeatable.')]
JacobianOpt = Annotated[str, typer.Option(
    "--jacobian", help=f"Newton matrix: {' | '.join(JACOBIANS)} (K_T, its first term, or K_T frozen at the undeformed state).")]
LineSearchOpt = Annotated[bool, typer.Option("--line-search/--no-line-search", help="Backtracking line search.")]
MaxIterOpt = Annotated[int, typer.Option("--max-iterations", help="Newton iterations per solve.")]
JsonOpt = Annotated[Path | None, typer.Option("--json", metavar="OUT.json", help="Write the results as JSON.")]
PlotOpt = Annotated[Path | None, typer.Option("--plot", metavar="OUT.png|svg", help="Write a figure.")]


# --- console and errors --------------------------------------------------------------------
def _consoles() -> tuple[Console, Console]:
    """(stdout, stderr) consoles, made per command so they follow the current streams. Output
    that is not a terminal (a file, a pipe) gets wide lines rather than squeezed tables,
    unless COLUMNS says otherwise."""
    out = Console()
    if not out.is_terminal and "COLUMNS" not in os.environ:
        out = Console(width=_FILE_WIDTH)
    return out, Console(stderr=True, highlight=False)


def _table(title: str | None, *columns: str, text: int = 1) -> Table:
    """A table whose first `text` columns are words and the others numbers (right-aligned,
    folded rather than cut when the console is narrow)."""
    table = Table(title=escape(title) if title else None, title_justify="left")
    for k, head in enumerate(columns):
        if k < text:
            table.add_column(escape(head))
        else:
            table.add_column(escape(head), justify="right", overflow="fold")
    return table


@contextmanager
def _user_errors(err: Console) -> Iterator[None]:
    """Turn problems with the document or the options into one red line and exit code 2."""
    try:
        yield
    except (MechanismError, OptionError) as exc:
        err.print(f"[bold red]error:[/bold red] {escape(str(exc))}", soft_wrap=True)
        raise typer.Exit(EXIT_ERROR) from None


def _number(value: float, unit: str | None = None) -> str:
    """Six significant figures, with the unit when given."""
    text = f"{value:.6g}"
    return f"{text} {unit}" if unit else text


def _write_json(path: Path, payload: dict) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(plain(payload), indent=2))
    except OSError as exc:
        raise OptionError("--json", f"cannot write {path}: {exc.strerror}") from None


def _check_plot_option(plot: Path | None) -> None:
    if plot is not None and plot.suffix.lower() not in PLOT_SUFFIXES:
        raise OptionError("--plot", f"cannot tell the figure format of '{plot}': use a name ending in "
                          f"{' or '.join(PLOT_SUFFIXES)}")


def _save_plot(draw, *args) -> None:
    try:
        draw(*args)
    except OSError as exc:
        raise OptionError("--plot", f"cannot write {args[-1]}: {exc.strerror}") from None


# --- building the mechanism ----------------------------------------------------------------
def _choice(option: str, value: str | None, choices: tuple[str, ...]) -> None:
    if value is not None and value not in choices:
        raise OptionError(option, f"unknown choice '{value}' (choose from {', '.join(choices)})")


def _overrides(sets: list[str] | None) -> dict[str, float | str]:
    """--set POINTER=VALUE items: VALUE as a number (document units) or a quantity string."""
    out: dict[str, float | str] = {}
    for item in sets or []:
        pointer, sep, value = item.partition("=")
        pointer, value = pointer.strip(), value.strip()
        if not sep or not pointer or not value:
            raise OptionError("--set", f"expected POINTER=VALUE, got '{item}'")
        if not pointer.startswith("/"):
            raise OptionError("--set", f"'{pointer}' is not a JSON pointer (like /loads/actuation/force/1)")
        try:
            out[pointer] = float(value)
        except ValueError:
            out[pointer] = value
    return out


def _mechanism(document: Path, model: str | None, sets: list[str] | None) -> Mechanism:
    _choice("--model", model, MODELS)
    overrides = _overrides(sets)
    mech = compile_mechanism(load_document(document), model=model)
    return mech.with_values(overrides) if overrides else mech


def _newton_options(jacobian: str, line_search: bool, max_iterations: int) -> NewtonOptions:
    _choice("--jacobian", jacobian, JACOBIANS)
    if max_iterations < 1:
        raise OptionError("--max-iterations", f"must be at least 1, got {max_iterations}")
    return NewtonOptions(max_iterations=max_iterations, line_search=line_search, jacobian=jacobian)


def _field_value(mech: Mechanism, pointer: str, text: str, option: str) -> float:
    """A value of numeric field `pointer` given on the command line, in document units."""
    kind = mech.parameter_kind(pointer)
    value: float | str
    try:
        value = float(text)
    except ValueError:
        value = text
    return quantity_to_si(value, kind, mech.doc_unit(kind), option) / mech.doc_factor(kind)


def _output_value(mech: Mechanism, name: str, text: str, option: str) -> float:
    """A value of output `name` given on the command line, in document units."""
    try:
        unit = output_unit(mech, name)
    except KeyError:
        raise OptionError(option, f"unknown output '{name}' ({_output_hint(mech)})") from None
    kind = mech.graphs.output_kinds[mech.graphs.output_names.index(name)]
    value: float | str
    try:
        value = float(text)
    except ValueError:
        value = text
    return quantity_to_si(value, kind, unit, option) / mech.doc_factor(kind)


def _output_hint(mech: Mechanism) -> str:
    names = [n for n in mech.graphs.output_names if not n.startswith("elements.")]
    return "outputs: " + ", ".join(names[:12]) + (", ..." if len(names) > 12 else "")


# --- solve ---------------------------------------------------------------------------------
def _print_solution(out: Console, result: EquilibriumResult) -> None:
    mech = result.mechanism
    structure = mech.structure
    values = result.outputs()
    L, A = mech.doc_unit("length"), mech.doc_unit("angle")
    F, M, S = mech.doc_unit("force"), mech.doc_unit("moment"), mech.doc_unit("stress")

    bodies = _table("bodies: pose of the reference point, and its displacement", "body", "support",
                    f"x [{L}]", f"y [{L}]", f"angle [{A}]", f"dx [{L}]", f"dy [{L}]", f"rotation [{A}]", text=2)
    for b, name in enumerate(structure.bodies):
        row = structure.prescribed[b]
        support = "fixed" if all(v == "" for v in row) else (
            "prescribed" if any(v is not None for v in row) else "free")
        x, y, angle = (values[f"bodies.{name}.{c}"] for c in ("x", "y", "angle"))
        x0, y0 = mech.value(f"/bodies/{name}/position/0"), mech.value(f"/bodies/{name}/position/1")
        angle0 = mech.value(f"/bodies/{name}/angle")
        bodies.add_row(name, support, *(_number(v) for v in (x, y, angle, x - x0, y - y0, angle - angle0)))
    out.print(bodies)

    named = _table("outputs", "output", "value", "unit")
    named.columns[2].justify = "left"
    named.columns[2].overflow = "ellipsis"
    for name in mech.graphs.output_names:
        if name.split(".", 1)[0] in mech.document.outputs:
            named.add_row(name, _number(values[name]), escape(output_unit(mech, name)))
    if named.row_count:
        out.print(named)

    supported = [n for b, n in enumerate(structure.bodies) if any(v is not None for v in structure.prescribed[b])]
    if supported:
        reactions = _table("support reactions (about the body's reference point)",
                           "body", f"Fx [{F}]", f"Fy [{F}]", f"M [{M}]")
        for name in supported:
            reactions.add_row(name, *(_number(values[f"reactions.{name}.{q}"]) for q in ("Fx", "Fy", "M")))
        out.print(reactions)

    beams = structure.of_family("curved_beam")
    if beams:
        models = sorted({f.model for f in beams})
        heads = ["flexure", "bodies"] + (["model"] if len(models) > 1 else [])
        flexures = _table(f"flexures ({models[0]} model)" if len(models) == 1 else "flexures",
                          *heads, f"rotation [{A}]", f"M end [{M}]", f"σ start [{S}]", f"σ end [{S}]",
                          f"σ max [{S}]", text=len(heads))
        for f in beams:
            e = f"elements.{f.name}"
            cells = [f.name, f"{structure.bodies[f.start_body]}→{structure.bodies[f.end_body]}"]
            cells += [f.model] if len(models) > 1 else []
            cells += [_number(values[f"{e}.{q}"]) for q in ("rotation", "M", "stress_start", "stress_end", "stress_max")]
            flexures.add_row(*cells)
        out.print(flexures)
    out.print(f"strain energy: {_number(values['energy'], mech.doc_unit('energy'))}")


def _print_stiffness(out: Console, kt: TangentStiffness) -> None:
    """K_T in blocks of columns that fit the console; K[i, j] in (row unit)/(column unit)."""
    n = len(kt.coordinates)
    label = max(len(f"{c} [{u}]") for c, u in zip(kt.coordinates, kt.row_units)) + 3
    per_block = max(1, (out.width - label) // 17)
    out.print(escape("tangent stiffness K_T = dR/dz at the solution: row i is the generalized force on "
                     "coordinate i, column j a displacement; K[i, j] in (row unit)/(column unit)"))
    for first in range(0, n, per_block):
        columns = range(first, min(n, first + per_block))
        table = _table(None, "R \\ z", *(f"{kt.coordinates[j]} [{kt.column_units[j]}]" for j in columns))
        for i in range(n):
            table.add_row(escape(f"{kt.coordinates[i]} [{kt.row_units[i]}]"),
                          *(_number(kt.K[i, j]) for j in columns))
        out.print(table)


def _stiffness_dict(kt: TangentStiffness) -> dict:
    return {"coordinates": kt.coordinates, "row_units": kt.row_units, "column_units": kt.column_units,
            "K": kt.K, "terms": kt.terms}


def _print_status(out: Console, result: EquilibriumResult) -> None:
    unit = result.mechanism.doc_unit("force")
    colour = "green" if result.converged else "red"
    out.print(f"status: [bold {colour}]{result.status}[/bold {colour}] after {result.iterations} iterations, "
              f"residual {_number(result.residual_norm_force, unit)}, {result.seconds:.3g} s")
    if not result.converged:
        out.print(f"diagnostics: {escape(result.message or 'no message')}; residual history "
                  f"(nondimensional) {', '.join(_number(h) for h in result.history[-6:])}")


@app.command()
def solve(
    document: DocArg,
    model: ModelOpt = None,
    sets: SetOpt = None,
    jacobian: JacobianOpt = "full",
    line_search: LineSearchOpt = True,
    max_iterations: MaxIterOpt = 50,
    json_out: JsonOpt = None,
    plot: PlotOpt = None,
    stiffness: Annotated[bool, typer.Option("--stiffness", help="Print the tangent stiffness K_T at the solution.")] = False,
) -> None:
    """Solve the equilibrium of a mechanism under its loads."""
    out, err = _consoles()
    with _user_errors(err):
        _check_plot_option(plot)
        options = _newton_options(jacobian, line_search, max_iterations)
        mech = _mechanism(document, model, sets)
        result = solve_equilibrium(mech, options)
        kt = tangent_stiffness(mech, result.z) if stiffness else None

        out.print(f"[bold]{escape(mech.document.name)}[/bold]  ({escape(str(document))})")
        for pointer in _overrides(sets):
            out.print(f"  {pointer} = {_number(mech.value(pointer), mech.doc_unit(mech.parameter_kind(pointer)))}")
        _print_status(out, result)
        if result.converged:
            _print_solution(out, result)
            for note in result.summary().get("warnings", []):
                out.print(f"[yellow]warning:[/yellow] {escape(note)}")
        else:
            out.print("[yellow]no equilibrium found: the last iterate is not reported as a solution[/yellow]")
        if kt is not None:
            _print_stiffness(out, kt)

        if json_out is not None:
            payload = {"document": str(document), "name": mech.document.name, "model": model,
                       "overrides": _overrides(sets), **result.summary()}
            if kt is not None:
                payload["stiffness"] = _stiffness_dict(kt)
            _write_json(json_out, payload)
            out.print(f"wrote {escape(str(json_out))}")
        if plot is not None:
            from service.plotting import plot_configuration

            _save_plot(plot_configuration, result, plot)
            out.print(f"wrote {escape(str(plot))}")
    if not result.converged:
        raise typer.Exit(EXIT_NOT_CONVERGED)


# --- inverse (links) ------------------------------------------------------------------------
@app.command()
def inverse(
    document: DocArg,
    sets: SetOpt = None,
    h: Annotated[list[str] | None, typer.Option("--internal-force", metavar="LINK.h=VALUE",
                                                help="Replace an internal force of the document's inverse section (repeatable).")] = None,
    max_iterations: MaxIterOpt = 50,
    json_out: JsonOpt = None,
) -> None:
    """Link inverse (seed 002 Sec. 5.3): initial shapes and unknown loads from the deformed
    shapes and internal forces of the document's `inverse` section."""
    from service.link_inverse import inverse_links

    out, err = _consoles()
    with _user_errors(err):
        mech = _mechanism(document, None, sets)
        spec = mech.document.inverse
        if spec is None:
            raise MechanismError("/inverse", "the document has no inverse section (shapes, internal_forces, unknown_loads)")
        forces = {name: dict(values) for name, values in spec.internal_forces.items()}
        for item in h or []:
            target, sep, text = item.partition("=")
            link, dot, component = target.strip().rpartition(".")
            if not sep or not dot or component not in ("h", "v"):
                raise OptionError("--internal-force", f"expected LINK.h=VALUE or LINK.v=VALUE, got '{item}'")
            try:
                forces.setdefault(link, {})[component] = float(text)
            except ValueError:
                raise OptionError("--internal-force", f"'{text}' is not a number") from None
        result = inverse_links(mech, spec.shapes, forces, spec.unknown_loads,
                               NewtonOptions(max_iterations=max_iterations))
        out.print(f"[bold]{escape(mech.document.name)}[/bold]  ({escape(str(document))}): link inverse")
        given = ", ".join(f"{name}.{c} = {_number(v, mech.document.units.force)}"
                          for name, values in forces.items() for c, v in values.items())
        out.print(f"given internal forces: {escape(given)}")
        out.print(f"status: {result.status} after {result.iterations} iterations"
                  + (f" ({escape(result.message)})" if result.message else ""))
        if result.converged:
            table = _table("unknown loads", "field", "value")
            for pointer, value in result.loads.items():
                table.add_row(pointer, _number(value, mech.doc_unit(mech.parameter_kind(pointer))))
            out.print(table)
            table = _table("links", "link", "h", "v", "M start", "M end", "eta(0) [rad]", "eta(1) [rad]")
            for name, values in result.links.items():
                table.add_row(name, *(_number(values[k]) for k in ("h", "v", "M_start", "M_end")),
                              _number(values["eta"][0]), _number(values["eta"][-1]))
            out.print(table)
        if json_out is not None:
            _write_json(json_out, {"document": str(document), "name": mech.document.name,
                                   "internal_forces": forces, **result.__dict__})
            out.print(f"wrote {escape(str(json_out))}")
    if not result.converged:
        raise typer.Exit(EXIT_NOT_CONVERGED)


# --- optimize and trace ----------------------------------------------------------------------
@app.command()
def optimize(
    document: DocArg,
    sets: SetOpt = None,
    starts: Annotated[int | None, typer.Option(min=1, max=64, help="Number of starts (default: the document's).")] = None,
    sensitivity: Annotated[list[str] | None, typer.Option(
        "--sensitivity", metavar="PATH", help="Also give d(optimum)/d(field) for this numeric field (repeatable).")] = None,
    json_out: JsonOpt = None,
) -> None:
    """Solve the design problem of the document's `optimize` section: one NLP over the design
    variables and the equilibrium of every load case (IPOPT, exact derivatives)."""
    from service.design import design_problem
    from service.optimize import combine, prepare, run_start
    from service.sensitivity import optimum_sensitivities

    out, err = _consoles()
    with _user_errors(err):
        mech = _mechanism(document, None, sets)
        spec = mech.document.optimize
        if spec is None:
            raise MechanismError("/optimize", "the document has no optimize section (design, objective, constraints)")
        if starts is not None:
            spec = spec.model_copy(update={"starts": starts})
        problem = design_problem(mech, spec)
        prepared = prepare(problem)
        runs = []
        for k in range(spec.starts):
            runs.append(run_start(prepared, k))
            if spec.starts > 1:
                err.print(f"start {k + 1}/{spec.starts}: {runs[-1].status}, objective {runs[-1].objective:.6g}")
        result = combine(problem, runs, sum(r.seconds for r in runs))
        best = result.best
        units = mech.doc_unit(problem.objective.kind)
        out.print(f"[bold]{escape(mech.document.name)}[/bold]  ({escape(str(document))}): optimize")
        out.print(f"status: {result.status}" + (f" ({escape(result.message)})" if result.message else ""))
        report = result.summary()
        if best is not None:
            out.print(f"objective {spec.objective.output}: {_number(best.objective, units)}  "
                      f"({best.iterations} IPOPT iterations, {best.seconds:.3g} s, equilibrium residual "
                      f"{best.equilibrium_residual:.2g})")
            table = _table("design", "field", "start", "optimum", "lower", "upper", "multiplier")
            for k, path in enumerate(problem.paths):
                unit = mech.doc_unit(mech.parameter_kind(path))
                table.add_row(path, _number(best.design_start[path], unit), _number(best.design[path], unit),
                              _number(problem.lower[k]), _number(problem.upper[k]),
                              _number(best.multipliers["design"][k]))
            out.print(table)
            if best.constraints:
                table = _table("constraints", "output", "case", "value", "lower", "upper", "active", "multiplier")
                for row in best.constraints:
                    table.add_row(row["output"], row["case"], _number(row["value"]),
                                  "-" if row["lower"] is None else _number(row["lower"]),
                                  "-" if row["upper"] is None else _number(row["upper"]),
                                  "yes" if row["active"] else "no", _number(row["multiplier"]))
                out.print(table)
            if sensitivity and best.succeeded:
                sens = optimum_sensitivities(prepared, best, list(sensitivity))
                table = _table("sensitivities of the optimum", "of", *sensitivity)
                for name, row, row_units in zip(sens.outputs, sens.matrix, sens.units):
                    table.add_row(name, *(_number(v, u) for v, u in zip(row, row_units)))
                out.print(table)
                report["sensitivities"] = sens.to_dict()
        if json_out is not None:
            _write_json(json_out, {"document": str(document), **report})
            out.print(f"wrote {escape(str(json_out))}")
    if result.status not in ("optimal", "acceptable"):
        raise typer.Exit(EXIT_NOT_CONVERGED)


@app.command()
def trace(
    document: DocArg,
    path: Annotated[str, typer.Option(help="The numeric field to follow, e.g. /loads/P/force/1.")],
    stop: Annotated[float, typer.Option(help="Stop once the field passes this value (document units).")],
    step: Annotated[float, typer.Option(help="First arc-length step, document units of the field.")],
    sets: SetOpt = None,
    max_points: Annotated[int, typer.Option(min=2, max=100_000)] = 400,
    json_out: JsonOpt = None,
) -> None:
    """Pseudo-arc-length continuation of the equilibrium path through limit points (snap-through),
    with the stability of every point and the limit loads located exactly."""
    from service.continuation import trace_path

    out, err = _consoles()
    with _user_errors(err):
        mech = _mechanism(document, None, sets)
        try:
            mech.parameter_index(path)
        except MechanismError as exc:
            raise OptionError("--path", exc.problem) from None
        if not step > 0:
            raise OptionError("--step", f"must be positive, got {step:g}")
        result = trace_path(mech, path, stop, step, max_points)
        x_name, y_name = _default_xy(mech)
        shown = y_name.replace(".y", ".dy") if y_name.replace(".y", ".dy") in mech.graphs.output_names else y_name
        out.print(f"[bold]{escape(mech.document.name)}[/bold]  ({escape(str(document))}): path of {path}")
        out.print(f"status: {result.status}, {len(result.points)} points, {result.seconds:.3g} s"
                  + (f" ({escape(result.message)})" if result.message else ""))
        table = _table("limit points", "kind", f"{path} [{result.unit}]", f"{shown} [{output_unit(mech, shown)}]",
                       "after point")
        for lp in result.limit_points:
            table.add_row(lp.kind, _number(lp.value), _number(lp.outputs[shown]), str(lp.after_point))
        out.print(table)
        table = _table("path", "point", f"{path} [{result.unit}]", f"{shown} [{output_unit(mech, shown)}]", "stable")
        n = len(result.points)
        for i in sorted(set(np.linspace(0, n - 1, min(n, 12)).round().astype(int).tolist())):
            pt = result.points[i]
            table.add_row(str(i), _number(pt.value), _number(pt.outputs[shown]),
                          {True: "yes", False: "no", None: "?"}[pt.stability.stable])
        out.print(table)
        if json_out is not None:
            _write_json(json_out, {"document": str(document), **result.to_dict()})
            out.print(f"wrote {escape(str(json_out))}")
    if result.status != "completed":
        raise typer.Exit(EXIT_NOT_CONVERGED)


# --- sweep ---------------------------------------------------------------------------------
def _default_xy(mech: Mechanism) -> tuple[str, str]:
    """The first point output, else the first body that is not fixed."""
    if mech.structure.points:
        name = mech.structure.points[0].name
    else:
        free = [b for b, row in enumerate(mech.structure.prescribed) if any(v is None for v in row)]
        name = f"bodies.{mech.structure.bodies[free[0] if free else 0]}"
    return f"{name}.x", f"{name}.y"


def _sweep_table(mech: Mechanism, label: str, result, x_output: str, y_output: str) -> Table:
    n = len(result.values)
    rows = sorted(set(np.linspace(0, n - 1, min(n, 6)).round().astype(int).tolist()))
    unit = mech.doc_unit(mech.parameter_kind(result.path))
    converged = sum(s == "converged" for s in result.status)
    table = _table(f"{label}: {n} points, {converged} converged, {result.seconds:.3g} s",
                   "point", f"{result.path} [{unit}]", f"{x_output} [{output_unit(mech, x_output)}]",
                   f"{y_output} [{output_unit(mech, y_output)}]", "status", "iterations")
    table.columns[0].justify = "right"
    table.columns[4].justify = "left"
    table.columns[4].overflow = "ellipsis"
    for i in rows:
        table.add_row(str(i), _number(result.values[i]), _number(result.outputs[x_output][i]),
                      _number(result.outputs[y_output][i]), result.status[i], str(result.iterations[i]))
    return table


def _curve_label(mech: Mechanism, model: str | None) -> str:
    elements = mech.structure.elements
    materials = sorted({t.material for t in elements if hasattr(t, "material")})
    models = sorted({t.model for t in mech.structure.of_family("curved_beam")}
                    | {"exact" for t in mech.structure.of_family("link") if mech.document.elements[t.name].type == "curved_beam"})
    parts = [", ".join(materials)] if len(materials) == 1 else []
    parts.append(model or (models[0] if len(models) == 1 else "mixed models"))
    return ", ".join(parts)


@app.command()
def sweep(
    document: DocArg,
    path: Annotated[str | None, typer.Option("--path", metavar="POINTER", help="Numeric field to sweep (default: the document's sweep section).")] = None,
    start: Annotated[str | None, typer.Option("--start", help="First value (document units or a quantity).")] = None,
    stop: Annotated[str | None, typer.Option("--stop", help="Last value.")] = None,
    steps: Annotated[int | None, typer.Option("--steps", help="Number of steps (points = steps + 1); default 100.")] = None,
    until: Annotated[str | None, typer.Option("--until", metavar="OUTPUT=VALUE", help="End where OUTPUT reaches VALUE, instead of --stop.")] = None,
    model: ModelOpt = None,
    compare_models: Annotated[bool, typer.Option("--compare-models", help=f"Sweep with each model ({', '.join(MODELS)}).")] = False,
    restart: Annotated[str, typer.Option("--restart", help=f"Newton start at each point: {' | '.join(RESTARTS)}.")] = "previous",
    sets: SetOpt = None,
    jacobian: JacobianOpt = "full",
    line_search: LineSearchOpt = True,
    max_iterations: MaxIterOpt = 50,
    json_out: JsonOpt = None,
    plot: PlotOpt = None,
    x_output: Annotated[str | None, typer.Option("--x-output", help="Output on the horizontal axis (default: the first point output's x).")] = None,
    y_output: Annotated[str | None, typer.Option("--y-output", help="Output of the trajectory's vertical axis (default: its y).")] = None,
) -> None:
    """Sweep a numeric field (a load, by default the document's sweep section) with continuation."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from models.document import SweepSpec, SweepUntil
    from service.sweep import run_sweep_spec

    out, err = _consoles()
    failed = False
    with _user_errors(err):
        _check_plot_option(plot)
        _choice("--restart", restart, RESTARTS)
        if compare_models and model is not None:
            raise OptionError("--compare-models", "runs every model; leave out --model")
        if path is None:
            given = [name for name, v in (("--start", start), ("--stop", stop), ("--steps", steps),
                                          ("--until", until)) if v is not None]
            if given:
                raise OptionError(given[0], "needs --path (without --path the document's sweep section is run)")
        else:
            if start is None:
                raise OptionError("--start", "required with --path")
            if (stop is None) == (until is None):
                raise OptionError("--stop", "give exactly one of --stop and --until with --path")
            if steps is not None and steps < 1:
                raise OptionError("--steps", f"must be at least 1, got {steps}")
        options = _newton_options(jacobian, line_search, max_iterations)
        models = list(MODELS) if compare_models else [model]
        mechs = [_mechanism(document, m, sets) for m in models]
        first = mechs[0]
        if path is None and first.document.sweep is None:
            raise MechanismError("/sweep", "the document declares no sweep: give --path, --start and --stop or --until")
        swept = path if path is not None else first.document.sweep.path
        first.parameter_index(swept)
        default_x, default_y = _default_xy(first)
        x_output, y_output = x_output or default_x, y_output or default_y
        for option, name in (("--x-output", x_output), ("--y-output", y_output)):
            if name not in first.graphs.output_names:
                raise OptionError(option, f"unknown output '{name}' ({_output_hint(first)})")
        if until is not None:
            until_output, sep, until_text = until.partition("=")
            if not sep or not until_output.strip() or not until_text.strip():
                raise OptionError("--until", f"expected OUTPUT=VALUE, got '{until}'")
            until_output = until_output.strip()
            goal = _output_value(first, until_output, until_text.strip(), "--until")
        if path is not None:
            first_value = _field_value(first, swept, start, "--start")
            last_value = _field_value(first, swept, stop, "--stop") if stop is not None else None
        unit = first.doc_unit(first.parameter_kind(swept))
        if path is None:
            spec = first.document.sweep
        else:
            spec = SweepSpec(path=swept, start=first_value, stop=last_value,
                             steps=100 if steps is None else steps,
                             until=SweepUntil(output=until_output, equals=goal) if until is not None else None)
        goal_text = None
        if spec.until is not None:
            equals = spec.until.equals
            if isinstance(equals, (int, float)):
                equals = _number(equals, output_unit(first, spec.until.output))
            goal_text = f"{spec.until.output} = {equals}"

        out.print(f"[bold]{escape(first.document.name)}[/bold]  ({escape(str(document))}): "
                  f"sweeping {escape(f'{swept} [{unit}]')}, restart from {restart}")
        curves = []
        records = []
        with Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                      TimeElapsedColumn(), console=err, transient=True, disable=not err.is_terminal) as progress:
            for mech, m in zip(mechs, models):
                label = _curve_label(mech, m)
                task = progress.add_task(label, total=None)

                def advance(done: int, total: int, task=task) -> None:
                    progress.update(task, completed=done, total=total)

                result, target = run_sweep_spec(mech, spec, options, restart, advance)
                if result is None:  # the end of the path (a target output value) was not reached
                    progress.update(task, visible=False)
                    eq = target.equilibrium
                    out.print(f"{label}: target {goal_text} not reached: status "
                              f"[bold red]{target.status}[/bold red] after {eq.iterations} iterations, "
                              f"residual {_number(eq.residual_norm_force, mech.doc_unit('force'))}; "
                              f"{escape(eq.message or 'no message')}")
                    records.append({"label": label, "model": m, "target": _target_dict(target, goal_text, unit)})
                    failed = True
                    continue
                curves.append((label, result))
                records.append({"label": label, "model": m, "sweep": result.to_dict(),
                                "target": _target_dict(target, goal_text, unit) if target else None})
                progress.update(task, visible=False)
                out.print(_sweep_table(mech, label, result, x_output, y_output))
                if target is not None:
                    out.print(f"{label}: {goal_text} at {field_label(swept)} = "
                              f"[bold]{_number(target.value, unit)}[/bold]")
                if not result.all_converged:
                    failed = True
                    bad = [i for i, s in enumerate(result.status) if s != "converged"]
                    out.print(f"[red]{label}: {len(bad)} of {len(result.status)} points did not converge[/red] "
                              f"(first: point {bad[0]}, {swept} = {_number(result.values[bad[0]], unit)}, "
                              f"status {result.status[bad[0]]}, residual "
                              f"{_number(result.residual_norms[bad[0]] / mech.nd_per_doc('force'), mech.doc_unit('force'))}, "
                              f"{result.iterations[bad[0]]} iterations)")

        if json_out is not None:
            _write_json(json_out, {"document": str(document), "name": first.document.name, "path": swept,
                                   "unit": unit, "restart": restart, "curves": records})
            out.print(f"wrote {escape(str(json_out))}")
        if plot is not None and curves:
            from service.plotting import plot_sweeps

            _save_plot(plot_sweeps, curves, x_output, y_output, swept, plot)
            out.print(f"wrote {escape(str(plot))}")
    if failed:
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _target_dict(target, goal_text: str | None, unit: str) -> dict:
    return {"goal": goal_text, "status": target.status, "value": target.value, "unit": unit,
            "iterations": target.equilibrium.iterations, "message": target.equilibrium.message}


# --- examples ------------------------------------------------------------------------------
@app.command()
def examples() -> None:
    """List the example documents and their names."""
    out, err = _consoles()
    with _user_errors(err):
        directory = examples_directory()
        if directory is None:
            raise OptionError("examples", "no examples directory (looked in ./examples and next to the package)")
        table = Table(title=f"examples in {directory}", title_justify="left")
        table.add_column("file")
        table.add_column("name")
        for file in sorted(directory.glob("*.json")):
            try:
                data = json.loads(file.read_text())
                name = data.get("name", "") if isinstance(data, dict) else "(not a mechanism document)"
            except (OSError, json.JSONDecodeError) as exc:
                name = f"(unreadable: {exc})"
            table.add_row(file.name, escape(str(name)))
        out.print(table)


# --- batch ---------------------------------------------------------------------------------
@app.command()
def batch(
    directory: Annotated[Path, typer.Argument(help="Folder of mechanism documents (JSON or YAML).", show_default=False)],
    out: Annotated[Path, typer.Option("--out", help="Folder for the results (created).")],
    jacobian: JacobianOpt = "full",
    line_search: LineSearchOpt = True,
    max_iterations: MaxIterOpt = 50,
) -> None:
    """Solve every document of a folder (sweep it, if it declares a sweep); write one result file
    per document and summary.json. Exit 1 if any document failed; the others are still written."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from service.batch import batch_documents, run_batch

    out_console, err = _consoles()
    with _user_errors(err):
        if not directory.is_dir():
            raise OptionError("DIRECTORY", f"'{directory}' is not a folder")
        options = _newton_options(jacobian, line_search, max_iterations)
        documents = batch_documents(directory)
        if not documents:
            raise OptionError("DIRECTORY", f"no documents (*.json, *.yaml) in '{directory}'")
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OptionError("--out", f"cannot create {out}: {exc.strerror}") from None
        columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
        with Progress(*columns, console=err, transient=True) as bar:
            task = bar.add_task("batch", total=len(documents))

            def advance(path: Path, payload: dict) -> None:
                bar.update(task, advance=1, description=path.name)

            summary = run_batch(directory, out, options, advance)
        table = _table(f"{summary['documents']} documents -> {out}", "document", "analysis", "status", "seconds",
                       text=3)
        for row in summary["results"]:
            colour = "green" if row["status"] == "converged" else "red"
            table.add_row(escape(row["document"]), str(row["analysis"] or "-"),
                          f"[{colour}]{row['status']}[/{colour}]", f"{row['seconds']:.3g}")
        out_console.print(table)
        for row in summary["results"]:
            if row["status"] != "converged":
                out_console.print(f"[red]{escape(row['document'])}:[/red] {escape(row['message'])}")
        out_console.print(f"wrote {escape(str(out / 'summary.json'))}")
    if summary["failed"]:
        raise typer.Exit(EXIT_NOT_CONVERGED)


# --- serve ---------------------------------------------------------------------------------
@app.command()
def serve(
    host: Annotated[str | None, typer.Option("--host", help="Address to listen on (default FLEXMECH_HOST or 127.0.0.1).")] = None,
    port: Annotated[int | None, typer.Option("--port", help="Port (default FLEXMECH_PORT or 8000).")] = None,
) -> None:
    """Run the HTTP API with uvicorn. Settings come from FLEXMECH_* environment variables
    (database, Dask address, API keys, limits); by default an SQLite file and a process pool."""
    import uvicorn
    from pydantic import ValidationError

    from service.settings import Settings

    _, err = _consoles()
    try:
        settings = Settings()
    except ValidationError as exc:
        first = exc.errors()[0]
        where = "FLEXMECH_" + str(first["loc"][0]).upper() if first["loc"] else "settings"
        err.print(f"[bold red]error:[/bold red] {escape(where)}: {escape(first['msg'])}", soft_wrap=True)
        raise typer.Exit(EXIT_ERROR) from None
    # The app is named by import string so that the service layer never imports the api package.
    uvicorn.run("api.app:create_app", factory=True, host=host or settings.host, port=port or settings.port,
                log_level=settings.log_level)


if __name__ == "__main__":
    app()
