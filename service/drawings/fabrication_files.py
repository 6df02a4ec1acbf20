"""A mechanism's fabricated outlines (service.drawings.fabrication) as files: DXF by ezdxf (closed
LWPOLYLINEs, the curved beams' arcs as bulges: true arcs) and GDSII by gdstk (polygons; arcs
within the chord error). Coordinates in the document's length unit: DXF's $INSUNITS names it where
DXF has a code for it, GDS's library unit is it in metres. Layer names are fixed (LAYERS); GDS
layers are their numbers there, 1 to 4. Nothing of the document but its numbers enters a file."""

from __future__ import annotations

import io
import math
import re
import tempfile
from pathlib import Path

import numpy as np

from flexmech.models.units import unit_factor
from flexmech.service.drawings.fabrication import LAYERS, Fabrication, Outline

GDS_LAYERS = {name: k + 1 for k, name in enumerate(LAYERS)}  # bodies 1, flexures 2, anchors 3, deformed 4
CELL = "MECHANISM"
MAX_POINTS = 8190  # GDSII's most vertices in one boundary
_INSUNITS = {"in": 1, "ft": 2, "mm": 4, "cm": 5, "m": 6, "km": 7, "um": 13, "nm": 12}


def file_stem(name: str) -> str:
    """A file name from a document's name: letters, digits, '-', '_' and '.' only (the rest '_'),
    at most 60 characters, never empty or hidden."""
    stem = re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("._")[:60]
    return stem or "mechanism"


def dxf_bytes(drawn: Fabrication) -> bytes:
    import ezdxf

    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = _INSUNITS.get(drawn.unit.strip(), 0)  # 0: unitless (the unit is in the notes)
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
    library = gdstk.Library("FLEXMECH", unit=unit, precision=unit * min(1e-6, drawn.chord_error / 100))
    cell = library.new_cell(CELL)
    for outline in drawn.outlines:
        points = polygon(outline, drawn.chord_error)
        layer = GDS_LAYERS[outline.layer]
        if outline.closed:
            cell.add(gdstk.Polygon(points, layer=layer))
        else:  # a deformed centre line: a path of no width is no mask shape, a thin one is
            cell.add(gdstk.FlexPath(points, drawn.chord_error * 10, layer=layer))
    with tempfile.TemporaryDirectory(prefix="flexmech-gds-") as folder:
        path = Path(folder) / "drawing.gds"
        library.write_gds(path, max_points=MAX_POINTS)  # more would split an outline in two
        return path.read_bytes()


def polygon(outline: Outline, chord_error: float) -> np.ndarray:
    """The outline's vertices with every bulged segment replaced by points on its arc, so that no
    chord leaves the arc by more than chord_error."""
    out = []
    n = len(outline.points)
    for k in range(n if outline.closed else n - 1):
        a, b, bulge = outline.points[k], outline.points[(k + 1) % n], outline.bulges[k]
        out.append(a)
        if bulge:
            out.extend(_arc_points(a, b, bulge, chord_error))
    if not outline.closed:
        out.append(outline.points[-1])
    return np.array(out)


def _arc_points(a: np.ndarray, b: np.ndarray, bulge: float, chord_error: float) -> list[np.ndarray]:
    """Points strictly between a and b on the arc of this bulge."""
    theta = 4.0 * math.atan(bulge)  # included angle, signed (positive: counter-clockwise)
    chord = float(np.hypot(*(b - a)))
    radius = chord / (2.0 * abs(math.sin(theta / 2.0)))
    middle, normal = (a + b) / 2.0, np.array([-(b - a)[1], (b - a)[0]]) / chord
    centre = middle + normal * (chord / 2.0) / math.tan(theta / 2.0)  # left of a -> b for a ccw arc under 180 deg
    start = math.atan2(*(a - centre)[::-1])
    step = 2 * math.acos(max(-1.0, 1 - chord_error / radius)) if chord_error < radius else math.pi / 4
    count = max(2, math.ceil(abs(theta) / step))
    return [
        centre + radius * np.array([math.cos(start + theta * j / count), math.sin(start + theta * j / count)])
        for j in range(1, count)
    ]
