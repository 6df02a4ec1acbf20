"""`flexmech drawing DOC --dxf OUT.dxf --gds OUT.gds`: the fabricated outlines of every body and
flexure (service.drawings.fabrication) for the shop (DXF, true arcs) and the mask (GDSII), in the
document's length unit; --design draws the design an optimize report found, --set any values."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Annotated

import typer

from flexmech.api.cli.application import app
from flexmech.api.cli.common import OptionError, consoles, shown, user_errors
from flexmech.api.cli.options import DocArg, ModelOpt, SetOpt, mechanism, overrides

DesignOpt = Annotated[
    Path | None,
    typer.Option(
        "--design",
        metavar="REPORT.json",
        help="Draw the design of an optimize report (flexmech optimize ... --json); --set still wins.",
    ),
]


@app.command()
def drawing(
    document: DocArg,
    dxf: Annotated[Path | None, typer.Option("--dxf", metavar="OUT.dxf", help="Write a DXF file (true arcs).")] = None,
    gds: Annotated[
        Path | None, typer.Option("--gds", metavar="OUT.gds", help="Write a GDSII file (for a mask).")
    ] = None,
    deformed: Annotated[
        bool, typer.Option("--deformed", help="Also the centre lines at the equilibrium under the document's loads.")
    ] = False,
    chord_error: Annotated[
        float,
        typer.Option(
            "--chord-error", help="The farthest a polygon may leave a true arc (GDS, round corners), length unit."
        ),
    ] = 1e-4,
    model: ModelOpt = None,
    design: DesignOpt = None,
    sets: SetOpt = None,
) -> None:
    """Fabrication drawings: layers bodies, flexures, anchors (and deformed); GDS layers 1 to 4."""
    from flexmech.models import MechanismError
    from flexmech.service.drawings.fabrication import fabrication
    from flexmech.service.drawings.fabrication_files import dxf_bytes, gds_bytes

    out, err = consoles()
    with user_errors(err):
        if dxf is None and gds is None:
            raise OptionError("--dxf", "give --dxf OUT.dxf, --gds OUT.gds or both")
        values = {**(designed(design) if design is not None else {}), **overrides(sets)}
        mech = mechanism(document, model, None)
        mech = mech.with_values(values) if values else mech
        try:
            drawn = fabrication(mech, deformed, chord_error)
        except MechanismError as exc:  # the request's fields are this command's options
            option = {"/chord_error": "--chord-error", "/deformed": "--deformed"}.get(exc.pointer)
            if option is not None:
                raise OptionError(option, exc.problem) from None
            raise
        for option, path, write in (("--dxf", dxf, dxf_bytes), ("--gds", gds, gds_bytes)):
            if path is None:
                continue
            try:
                path.write_bytes(write(drawn))
            except OSError as exc:
                raise OptionError(option, f"cannot write {path}: {exc.strerror}") from None
            out.print(f"wrote {shown(str(path))}")
        out.print(summary(drawn, chord_error))


def designed(report: Path) -> dict[str, str]:
    """The design of an optimize report (`flexmech optimize ... --json`) as overrides: each
    pointer's value with the unit the report gives it ("0.00694 mm"), or a plain number (the
    document's unit) where it gives none."""
    try:
        data = json.loads(report.read_text())
    except OSError as exc:
        raise OptionError("--design", f"cannot read {report}: {exc.strerror}") from None
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise OptionError("--design", f"{report} is not JSON (an optimize report is)") from None
    design = data.get("design") if isinstance(data, dict) else None
    if not isinstance(design, dict) or data.get("analysis") != "optimize" or not design:
        raise OptionError("--design", f"{report} is no optimize report with a design (flexmech optimize ... --json)")
    units = data.get("units") if isinstance(data.get("units"), dict) else {}
    values = {}
    for pointer, value in design.items():
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
            raise OptionError("--design", f"the design's value at {pointer!r} is not a finite number")
        unit = units.get(pointer)
        values[pointer] = f"{value!r} {unit}" if isinstance(unit, str) and unit else value
    return values


def summary(drawn, chord_error: float) -> str:
    """One line: the outlines per layer, the unit, the chord error and the links' sampling."""
    counts = {layer: len(drawn.on(layer)) for layer in ("bodies", "anchors", "flexures", "deformed")}
    unit = shown(drawn.unit)
    line = ", ".join(f"{n} {layer}" for layer, n in counts.items() if n)
    line += f"; length unit {unit}; polygons within {chord_error:g} {unit} of the arcs and splines (GDS grid {drawn.grid:g} {unit})"
    if drawn.link_error:
        line += f"; links' splines about {drawn.link_error:.2g} {unit} from their centre lines"
    return line
