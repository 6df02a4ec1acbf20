"""The tables `flexmech solve` prints, rendered from an analysis report (document units) and
the compiled mechanism (which bodies, supports and flexures there are)."""

from __future__ import annotations

from rich.console import Console
from rich.table import Table

from flexmech.api.cli.common import number, shown, table_of
from flexmech.api.cli.quantities import exact_text
from flexmech.models import Mechanism
from flexmech.models.elements import FAMILIES
from flexmech.service.drawings.plotting import output_unit


def print_status(out: Console, report: dict) -> None:
    """Status, iterations, residual and time, as far as the analysis reports them; the
    diagnostics when it did not converge."""
    converged = report["status"] in ("converged", "finished")
    colour = "green" if converged else "red"
    line = f"status: [bold {colour}]{report['status']}[/bold {colour}]"
    if "iterations" in report:
        line += f" after {report['iterations']} iterations"
    if "residual_norm" in report:
        line += f", residual {number(report['residual_norm'], report['residual_unit'], kind='exact')}"
    if "seconds" in report:
        line += f", {report['seconds']:.3g} s"
    out.print(line)
    if not converged:
        line = f"diagnostics: {shown(report.get('message') or 'no message')}"
        if report.get("history"):
            line += f"; residual history (nondimensional) {', '.join(exact_text(h) for h in report['history'][-6:])}"
        out.print(line)


def print_solution(out: Console, mech: Mechanism, report: dict) -> None:
    """Bodies, named outputs, support reactions, flexures and the strain energy of a solution."""
    values = report["outputs"]
    for table in (
        bodies_table(mech, values),
        outputs_table(mech, values),
        reactions_table(mech, values),
        flexures_table(mech, values),
    ):
        if table is not None:
            out.print(table)
    out.print(f"strain energy: {number(values['energy'], mech.doc_unit('energy'), kind='energy')}")


def bodies_table(mech: Mechanism, values: dict) -> Table:
    structure = mech.structure
    L, A = mech.doc_unit("length"), mech.doc_unit("angle")
    table = table_of(
        "bodies: pose of the reference point, and its displacement",
        "body",
        "support",
        f"x [{L}]",
        f"y [{L}]",
        f"angle [{A}]",
        f"dx [{L}]",
        f"dy [{L}]",
        f"rotation [{A}]",
        text=2,
    )
    for b, name in enumerate(structure.bodies):
        row = structure.prescribed[b]
        support = (
            "fixed" if all(v == "" for v in row) else ("prescribed" if any(v is not None for v in row) else "free")
        )
        x, y, angle = (values[f"bodies.{name}.{c}"] for c in ("x", "y", "angle"))
        x0, y0 = mech.value(f"/bodies/{name}/position/0"), mech.value(f"/bodies/{name}/position/1")
        angle0 = mech.value(f"/bodies/{name}/angle")
        table.add_row(shown(name), support, x, y, angle, x - x0, y - y0, angle - angle0)
    return table


def outputs_table(mech: Mechanism, values: dict) -> Table | None:
    """The outputs the document names (None if it names none)."""
    table = table_of("outputs", "output", "value", "unit", unit_column=(1, 2))
    table.columns[2].justify = "left"
    table.columns[2].overflow = "ellipsis"
    for name in mech.graphs.output_names:
        if name.split(".", 1)[0] in mech.document.outputs:
            table.add_row(shown(name), values[name], output_unit(mech, name))
    return table if table.row_count else None


def reactions_table(mech: Mechanism, values: dict) -> Table | None:
    """Reactions of the supported bodies (None if no body is supported)."""
    structure = mech.structure
    supported = [n for b, n in enumerate(structure.bodies) if any(v is not None for v in structure.prescribed[b])]
    if not supported:
        return None
    F, M = mech.doc_unit("force"), mech.doc_unit("moment")
    table = table_of(
        "support reactions (about the body's reference point)", "body", f"Fx [{F}]", f"Fy [{F}]", f"M [{M}]"
    )
    for name in supported:
        table.add_row(shown(name), *(values[f"reactions.{name}.{q}"] for q in ("Fx", "Fy", "M")))
    return table


def flexures_table(mech: Mechanism, values: dict) -> Table | None:
    """Rotation, end moment and stresses of the curved beams (None if there are none); the
    model is a column only when the beams differ in it."""
    structure = mech.structure
    beams = [t for t in structure.elements if getattr(FAMILIES.of(t), "flexure_outputs", None)]
    if not beams:
        return None
    A, M, S = mech.doc_unit("angle"), mech.doc_unit("moment"), mech.doc_unit("stress")
    beam_models = sorted({f.model for f in beams})
    mixed = len(beam_models) > 1
    heads = ["flexure", "bodies"] + (["model"] if mixed else [])
    table = table_of(
        "flexures" if mixed else f"flexures ({beam_models[0]} model)",
        *heads,
        f"rotation [{A}]",
        f"M end [{M}]",
        f"σ start [{S}]",
        f"σ end [{S}]",
        f"σ max [{S}]",
        text=len(heads),
    )
    for f in beams:
        e = f"elements.{f.name}"
        cells = [shown(f.name), shown(f"{structure.bodies[f.start_body]}→{structure.bodies[f.end_body]}")]
        cells += [f.model] if mixed else []
        cells += [values[f"{e}.{q}"] for q in FAMILIES.of(f).flexure_outputs]
        table.add_row(*cells)
    return table


# The terms of K_T of Cammarata et al. 2022 (Eqs. 26-28), as service.solvers.stiffness names them.
STIFFNESS_TERMS = {
    "I": "term I of K_T (Cammarata et al. 2022, Eqs. 26-28): through the flexures' deformation",
    "II": "term II of K_T (Cammarata et al. 2022): through the body rotations that carry the flexures' ends",
    "III": "term III of K_T (Cammarata et al. 2022): through the tip displacement in the flexure frames "
    "(partial non-linear model)",
    "load": "load term of K_T: through the arms of forces applied away from a reference point",
}


def print_stiffness(out: Console, stiffness: dict) -> None:
    """K_T (service.solvers.reports.stiffness_dict) in blocks of columns that fit the console;
    K[i][j] in (row unit)/(column unit). Then each of its terms I, II, III and load that is
    not zero (curved-beam mechanisms without links have them), titled, in the same units."""
    out.print(
        shown(
            "tangent stiffness K_T = dR/dz at the solution: row i is the generalized force on "
            "coordinate i, column j a displacement; K[i, j] in (row unit)/(column unit)"
        )
    )
    if not stiffness["coordinates"]:
        out.print("K_T is empty: no body coordinate is free (every body is fixed or has a prescribed motion)")
        return
    floors = matrix_floors(stiffness)
    print_matrix(out, stiffness, stiffness["K"], floors)
    terms = stiffness.get("terms") or {}
    nonzero = {name for name, term in terms.items() if any(value != 0 for row in term for value in row)}
    for name, title in STIFFNESS_TERMS.items():
        if name in nonzero:
            out.print(shown(f"{title} (same units; the terms sum to K_T)"))
            print_matrix(out, stiffness, terms[name], floors)
    zero = [name for name in STIFFNESS_TERMS if name in terms and name not in nonzero]
    if zero:
        out.print(f"zero term{'s' if len(zero) > 1 else ''} of K_T here: {', '.join(zero)}")


def matrix_floors(stiffness: dict) -> dict[tuple[str, str], float]:
    """The noise floor of K_T's entries per (row unit, column unit): NOISE times the largest
    such entry of K_T (its terms' round-off, 3e-15 uN/deg beside entries of hundreds, is 0)."""
    from flexmech.service.display import NOISE

    largest: dict[tuple[str, str], float] = {}
    for i, row in enumerate(stiffness["K"]):
        for j, value in enumerate(row):
            key = (stiffness["row_units"][i], stiffness["column_units"][j])
            largest[key] = max(largest.get(key, 0.0), abs(value or 0.0))
    return {key: NOISE * value for key, value in largest.items()}


def print_matrix(
    out: Console, stiffness: dict, K: list[list[float | None]], floors: dict[tuple[str, str], float]
) -> None:
    """A matrix over the coordinates of `stiffness` (its units), in blocks of columns that fit
    the console; entries below their unit's floor (matrix_floors) as 0."""
    from flexmech.service.display import Display

    coordinates, rows, columns = (stiffness[k] for k in ("coordinates", "row_units", "column_units"))
    n = len(coordinates)
    label = max((len(f"{c} [{u}]") for c, u in zip(coordinates, rows)), default=0) + 3
    per_block = max(1, (out.width - label) // 17)
    for first in range(0, n, per_block):
        block = range(first, min(n, first + per_block))
        table = table_of(None, "R \\ z", *(f"{coordinates[j]} [{columns[j]}]" for j in block))
        for i in range(n):
            cells = (Display("", floor=floors.get((rows[i], columns[j]), 0.0)).text(K[i][j]) for j in block)
            table.add_row(shown(f"{coordinates[i]} [{rows[i]}]"), *cells)
        out.print(table)


def print_wrenches(out: Console, report: dict) -> None:
    """The inverse analysis: the wrench each body needs (loads plus supports)."""
    units = report["wrench_units"]
    table = table_of(
        "wrench each body needs (loads plus supports)",
        "body",
        f"Fx [{units['Fx']}]",
        f"Fy [{units['Fy']}]",
        f"M [{units['M']}]",
    )
    for body, wrench in report["wrenches"].items():
        table.add_row(shown(body), *(wrench[q] for q in ("Fx", "Fy", "M")))
    out.print(table)
