"""`flexmech drawing DOC --dxf OUT.dxf --gds OUT.gds`: the fabricated outlines of every body and
flexure (service.drawings.fabrication) for the shop (DXF, true arcs) and the mask (GDSII), in the
document's length unit; --set applies an optimized design's values."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flexmech.api.cli.application import app
from flexmech.api.cli.common import OptionError, consoles, shown, user_errors
from flexmech.api.cli.options import DocArg, ModelOpt, SetOpt, mechanism


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
    sets: SetOpt = None,
) -> None:
    """Fabrication drawings: layers bodies, flexures, anchors (and deformed); GDS layers 1 to 4."""
    from flexmech.service.drawings.fabrication import fabrication
    from flexmech.service.drawings.fabrication_files import dxf_bytes, gds_bytes

    out, err = consoles()
    with user_errors(err):
        if dxf is None and gds is None:
            raise OptionError("--dxf", "give --dxf OUT.dxf, --gds OUT.gds or both")
        if not chord_error > 0:
            raise OptionError("--chord-error", f"must be positive, got {chord_error:g}")
        mech = mechanism(document, model, sets)
        drawn = fabrication(mech, deformed, chord_error)
        for option, path, write in (("--dxf", dxf, dxf_bytes), ("--gds", gds, gds_bytes)):
            if path is None:
                continue
            try:
                path.write_bytes(write(drawn))
            except OSError as exc:
                raise OptionError(option, f"cannot write {path}: {exc.strerror}") from None
            out.print(f"wrote {shown(str(path))}")
        counts = {layer: len(drawn.on(layer)) for layer in ("bodies", "anchors", "flexures", "deformed")}
        out.print(
            ", ".join(f"{n} {layer}" for layer, n in counts.items() if n)
            + f"; length unit {shown(drawn.unit)}; arcs in GDS within {chord_error:g} {shown(drawn.unit)}"
            + (
                f"; links' centre lines within {drawn.link_chord_error:.2g} of their chords"
                if drawn.link_chord_error
                else ""
            )
        )
