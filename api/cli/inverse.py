"""`flexmech inverse`: the link inverse of the document's `inverse` section."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console

from flexmech.api.cli.application import app
from flexmech.api.cli.common import (
    EXIT_NOT_CONVERGED,
    OptionError,
    consoles,
    number,
    shown,
    table_of,
    user_errors,
    write_json,
)
from flexmech.api.cli.options import DocArg, JsonOpt, MaxIterOpt, SetOpt, mechanism

if TYPE_CHECKING:  # the link inverse is imported when the command runs
    from flexmech.models import Mechanism
    from flexmech.service.solvers.inverse_links import LinkInverseResult


def internal_forces(given: dict[str, dict[str, float]], items: list[str] | None) -> dict[str, dict[str, float]]:
    """The document's internal forces with the --internal-force LINK.h=VALUE items replacing them."""
    forces = {name: dict(values) for name, values in given.items()}
    for item in items or []:
        target, sep, text = item.partition("=")
        link, dot, component = target.strip().rpartition(".")
        if not sep or not dot or component not in ("h", "v"):
            raise OptionError("--internal-force", f"expected LINK.h=VALUE or LINK.v=VALUE, got '{item}'")
        try:
            forces.setdefault(link, {})[component] = float(text)
        except ValueError:
            raise OptionError("--internal-force", f"'{text}' is not a number") from None
    return forces


def print_link_inverse(out: Console, mech: Mechanism, forces: dict, result: LinkInverseResult) -> None:
    """The given internal forces, the status, and when converged the loads found and the links."""
    given = ", ".join(
        f"{name}.{c} = {number(v, mech.document.units.force)}"
        for name, values in forces.items()
        for c, v in values.items()
    )
    out.print(f"given internal forces: {shown(given)}")
    out.print(
        f"status: {result.status} after {result.iterations} iterations"
        + (f" ({shown(result.message)})" if result.message else "")
    )
    if not result.converged:
        return
    table = table_of("unknown loads", "field", "value", "unit", unit_column=(1, 2))
    for pointer, value in result.loads.items():
        table.add_row(shown(pointer), value, mech.doc_unit(mech.parameter_kind(pointer)))
    out.print(table)
    F, M = mech.doc_unit("force"), mech.doc_unit("moment")
    table = table_of(
        "links", "link", f"h [{F}]", f"v [{F}]", f"M start [{M}]", f"M end [{M}]", "eta(0) [rad]", "eta(1) [rad]"
    )
    for name, values in result.links.items():
        table.add_row(
            shown(name),
            *(values[k] for k in ("h", "v", "M_start", "M_end")),
            values["eta"][0],
            values["eta"][-1],
        )
    out.print(table)


@app.command()
def inverse(
    document: DocArg,
    sets: SetOpt = None,
    h: Annotated[
        list[str] | None,
        typer.Option(
            "--internal-force",
            metavar="LINK.h=VALUE",
            help="Replace an internal force of the document's inverse section (repeatable).",
        ),
    ] = None,
    max_iterations: MaxIterOpt = 50,
    json_out: JsonOpt = None,
) -> None:
    """Link inverse (Lan 2005 Sec. 5.3): initial shapes and unknown loads from the deformed
    shapes and internal forces of the document's `inverse` section."""
    from flexmech.models import MechanismError
    from flexmech.service.solvers.inverse_links import inverse_links
    from flexmech.service.solvers.newton import NewtonOptions

    out, err = consoles()
    with user_errors(err):
        mech = mechanism(document, None, sets)
        spec = mech.document.inverse
        if spec is None:
            raise MechanismError(
                "/inverse", "the document has no inverse section (shapes, internal_forces, unknown_loads)"
            )
        forces = internal_forces(spec.internal_forces, h)
        result = inverse_links(
            mech, spec.shapes, forces, spec.unknown_loads, NewtonOptions(max_iterations=max_iterations)
        )
        out.print(f"[bold]{shown(mech.document.name)}[/bold]  ({shown(str(document))}): link inverse")
        print_link_inverse(out, mech, forces, result)
        if json_out is not None:
            write_json(
                json_out,
                {"document": str(document), "name": mech.document.name, "internal_forces": forces, **result.__dict__},
            )
            out.print(f"wrote {shown(str(json_out))}")
    if not result.converged:
        raise typer.Exit(EXIT_NOT_CONVERGED)
