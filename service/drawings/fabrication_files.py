"""A mechanism's fabricated outlines (service.drawings.fabrication) as files: DXF by ezdxf (closed
LWPOLYLINEs, the curved beams' arcs as bulges: true arcs) and GDSII by gdstk (polygons; arcs
within the chord error). Coordinates in the document's length unit: DXF's $INSUNITS names it where
DXF has a code for its size, GDS's library unit is it in metres and its database unit the grid
(service.drawings.fabrication_costs). Layer names are fixed (LAYERS); GDS layers are their
numbers there, 1 to 4. Nothing of the document but its numbers enters a file; the file name a
service gives is the document's name through the one file-name mangling
(service.export.encoders.c_identifier)."""

from __future__ import annotations

import io
import math
import tempfile
from pathlib import Path

import numpy as np

from flexmech.models.units import unit_factor
from flexmech.service.drawings.fabrication import LAYERS, Fabrication, Outline
from flexmech.service.drawings.fabrication_costs import MAX_OUTLINE_POINTS
from flexmech.service.drawings.fabrication_geometry import arc_points
from flexmech.service.export.encoders import c_identifier

GDS_LAYERS = {name: k + 1 for k, name in enumerate(LAYERS)}  # bodies 1, flexures 2, anchors 3, deformed 4
CELL = "MECHANISM"
MAX_STEM = 60  # characters of a file name before its extension
# DXF's $INSUNITS codes by the unit's size in metres (0, none of these: unitless)
_INSUNITS = {
    0.0254: 1,  # inch
    0.3048: 2,  # foot
    1609.344: 3,  # mile
    1e-3: 4,
    1e-2: 5,
    1.0: 6,
    1e3: 7,
    2.54e-8: 8,  # microinch
    2.54e-5: 9,  # mil
    0.9144: 10,  # yard
    1e-10: 11,  # angstrom
    1e-9: 12,
    1e-6: 13,
    0.1: 14,
    10.0: 15,
    100.0: 16,
}


def file_stem(name: str) -> str:
    """A file name (before its extension) from a document's name: the one file-name mangling,
    lower-case ASCII letters, digits and single underscores, at most MAX_STEM characters;
    "mechanism" for a name with no ASCII letter or digit."""
    stem = c_identifier(name)[:MAX_STEM].rstrip("_")
    return stem if any(ch.isalnum() for ch in name if ch.isascii()) else "mechanism"


def insunits(unit: str) -> int:
    """DXF's $INSUNITS code of a length unit (0: unitless, when DXF has no code for its size)."""
    metres = unit_factor(unit, "length", "/units/length")
    return next((code for size, code in _INSUNITS.items() if math.isclose(size, metres, rel_tol=1e-12)), 0)


def dxf_bytes(drawn: Fabrication) -> bytes:
    import ezdxf

    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = insunits(drawn.unit)
    doc.header["$MEASUREMENT"] = 1
    for k, name in enumerate(LAYERS):
        doc.layers.add(name, color=k + 1)
    space = doc.modelspace()
    for outline in drawn.outlines:
        vertices = [(float(x), float(y), 0.0, 0.0, float(b)) for (x, y), b in zip(outline.points, outline.bulges)]
        space.add_lwpolyline(vertices, format="xyseb", close=outline.closed, dxfattribs={"layer": outline.layer})
    stream = io.StringIO()
    doc.write(stream)
    return stream.getvalue().encode("utf-8")


def gds_bytes(drawn: Fabrication) -> bytes:
    import gdstk

    unit = unit_factor(drawn.unit, "length", "/units/length")
    library = gdstk.Library("FLEXMECH", unit=unit, precision=unit * drawn.grid)
    cell = library.new_cell(CELL)
    for outline in drawn.outlines:
        points = polygon(outline, drawn.chord_error - drawn.grid)  # rounded to the grid: within the chord error
        layer = GDS_LAYERS[outline.layer]
        if outline.closed:
            cell.add(gdstk.Polygon(points, layer=layer))
        else:  # a deformed centre line: a GDSII PATH of width 0, a line and no mask shape
            cell.add(gdstk.FlexPath(points, 0, simple_path=True, layer=layer))
    with tempfile.TemporaryDirectory(prefix="flexmech-gds-") as folder:
        path = Path(folder) / "drawing.gds"
        library.write_gds(path, max_points=MAX_OUTLINE_POINTS)  # fabrication() allows no more in an outline
        return path.read_bytes()


def polygon(outline: Outline, tolerance: float) -> np.ndarray:
    """The outline's vertices with every bulged segment replaced by points on its arc, so that no
    chord leaves the arc by more than tolerance."""
    out = []
    n = len(outline.points)
    for k in range(n if outline.closed else n - 1):
        a, b, bulge = outline.points[k], outline.points[(k + 1) % n], outline.bulges[k]
        out.append(a)
        if bulge:
            out.extend(arc_points(a, b, bulge, tolerance))
    if not outline.closed:
        out.append(outline.points[-1])
    return np.array(out)
