"""The fabricated outline of a mechanism, for the shop (DXF) and the mask (GDS): every flexure and
link as the closed outline of its material, every body as a closed polygon, in the document's
length unit (service.drawings.fabrication_files writes them).

- A curved beam: two concentric arcs of radius r + h/2 and r - h/2 over its arc angle, joined at
  its ends by radial segments (the arcs are exact: DXF keeps them as arcs; GDS, which has none,
  takes polygons whose vertices lie on them, within the chord error).
- A link: its centre line offset by +-h/2 along its normals (h varying along a tapered section),
  closed across its ends, within the chord error of the cubic spline through the drawing's
  samples of the centre line (service.drawings.fabrication_links; the spline's own distance from
  the line estimated and reported).
- A body: a document gives no body outline, so the drawing makes one: the convex hull of its
  reference point, the points its flexures, links and point outputs attach at and the closed
  contact outlines it carries (a jaw polygon, a pin's circle, a hole: the material around it;
  the hole itself is not cut), grown by MARGIN_WIDTHS times the widest section attached to it
  (at least MARGIN_SPAN of the drawing's extent); round corners as polygons within the chord
  error. A fixed body is on the anchors layer.
- Springs, pins, sliders and contact objects on no body are no material: they are not drawn.
The layers: bodies, flexures (curved beams and links), anchors, and deformed (the centre lines at
the equilibrium under the document's loads, when asked). Names in the document are never layer
or block names: they are data, and stay out of the files' structure.

The work is costed before a vertex is made (service.drawings.fabrication_costs): at most 8190
vertices in an outline (GDSII's most in a boundary) and 200 000 in all, arcs as GDS polygons; the
GDS grid; a chord error that needs more is refused with one that fits."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.elements import FAMILIES
from flexmech.service.drawings.drawing import mechanism_drawing
from flexmech.service.drawings.fabrication_costs import check_costs, gds_grid
from flexmech.service.drawings.fabrication_geometry import convex_hull, grown_hull
from flexmech.service.drawings.fabrication_links import interpolation_error, link_outline

LAYERS = ("bodies", "flexures", "anchors", "deformed")
CHORD_ERROR = 1e-4  # of the length unit: the default distance a polygon may leave a true arc
MARGIN_WIDTHS = 4.0
MARGIN_SPAN = 0.01


@dataclass
class Outline:
    """One closed outline on a layer: vertices, and per vertex the bulge of the segment to the
    next (DXF's: tan of a quarter of the arc's included angle, positive counter-clockwise)."""

    layer: str
    kind: str  # curved_beam, link, body, deformed
    pointer: str  # of the element or body it draws: where a refusal points
    points: np.ndarray  # (n, 2)
    bulges: np.ndarray  # (n,)
    closed: bool = True
    arcs: list[tuple[float, float, float, float, float]] = field(default_factory=list)  # (cx, cy, r, from, to) deg


@dataclass
class Fabrication:
    unit: str
    chord_error: float
    outlines: list[Outline]
    link_error: float  # the largest estimated distance of a link's spline from its centre line
    grid: float  # the GDS grid (database unit), length unit: gds_grid

    def on(self, layer: str) -> list[Outline]:
        return [o for o in self.outlines if o.layer == layer]


def fabrication(mech: Mechanism, deformed: bool = False, chord_error: float = CHORD_ERROR) -> Fabrication:
    """The fabricated outlines of `mech` (its overrides applied); with `deformed`, also the centre
    lines at the equilibrium under the document's loads (MechanismError when it does not solve).
    A MechanismError at /chord_error when the outlines would need too many vertices or a finer
    grid than GDSII holds (service.drawings.fabrication_costs), counted before they are made."""
    if not (chord_error > 0 and math.isfinite(chord_error)):
        raise MechanismError("/chord_error", f"must be a positive number, got {chord_error:g}")
    unit = mech.doc_unit("length")
    drawing = mechanism_drawing(mech)
    outlines, widths, worst = _flexures(mech, drawing, chord_error)
    hulls = _body_hulls(drawing, widths)
    far = max([_farthest(o) for o in outlines] + [np.max(np.abs(h)) + m for h, m, _ in hulls.values()])
    grid = gds_grid(far, chord_error, unit)
    check_costs(outlines, [(h, m) for h, m, _ in hulls.values()], chord_error, far, unit)
    for body, (hull, margin, fixed) in hulls.items():
        loop = grown_hull(hull, margin, chord_error - grid)
        outlines.append(Outline("anchors" if fixed else "bodies", "body", f"/bodies/{body}", loop, np.zeros(len(loop))))
    if deformed:
        outlines += _deformed(mech)
    return Fabrication(unit, chord_error, outlines, worst, grid)


def _flexures(mech: Mechanism, drawing: dict, chord_error: float) -> tuple[list[Outline], dict[str, float], float]:
    """The outline of every curved beam and link; per body the widest section attached to it;
    the largest estimated distance of a link's spline from its centre line."""
    outlines, widths, worst = [], {}, 0.0
    points_of = {e["name"]: np.array(e["points"]) for e in drawing["elements"]}
    for name, element in mech.document.elements.items():
        drawn_as = getattr(FAMILIES.named(element.type), "fabricated", None)
        if drawn_as == "arc":
            h = _width(mech, element.section, f"/elements/{name}/section")
            outlines.append(_curved_beam(mech, name, element, h))
        elif drawn_as == "centre_line":
            h0, h1 = _widths(mech, element.section, f"/elements/{name}/section")
            h_end = h0 if h1 is None else h1
            pointer, samples = f"/elements/{name}", points_of[name]
            loop = link_outline(samples, h0, h_end, chord_error, mech.doc_unit("length"), pointer)
            outlines.append(Outline("flexures", "link", pointer, loop, np.zeros(len(loop))))
            worst, h = max(worst, interpolation_error(samples, pointer)), max(h0, h_end)
        else:
            continue
        for body in (element.from_, element.to):
            widths[body] = max(widths.get(body, 0.0), h)
    return outlines, widths, worst


def _farthest(outline: Outline) -> float:
    """The largest |x| or |y| the outline reaches (its arcs' too)."""
    reach = [float(np.max(np.abs(outline.points)))]
    reach += [max(abs(cx), abs(cy)) + r for cx, cy, r, _, _ in outline.arcs]
    return max(reach)


def _width(mech: Mechanism, section: str, pointer: str) -> float:
    h0, h1 = _widths(mech, section, pointer)
    if h1 is not None:
        raise MechanismError(pointer, f"section '{section}' is tapered: a curved beam's width is constant")
    return h0


def _widths(mech: Mechanism, section: str, pointer: str) -> tuple[float, float | None]:
    """(h, None) of a rectangle, (h_start, h_end) of a tapered one, in the length unit."""
    base = f"/sections/{section}"
    try:
        return mech.value(f"{base}/h"), None
    except MechanismError:
        pass
    try:
        return mech.value(f"{base}/h_start"), mech.value(f"{base}/h_end")
    except MechanismError:
        raise MechanismError(
            pointer, f"section '{section}' has no in-plane width h (a general section): a drawing needs one"
        ) from None


def _curved_beam(mech: Mechanism, name: str, element, h: float) -> Outline:
    base = f"/elements/{name}"
    cx, cy = (mech.value(f"{base}/center/{i}") for i in (0, 1))
    r = mech.value(f"{base}/radius")
    degrees = 180.0 / math.pi * mech.doc_factor("angle")
    start, sweep = mech.value(f"{base}/start_angle") * degrees, mech.value(f"{base}/arc_angle") * degrees
    sign = 1.0 if element.direction == "ccw" else -1.0
    end = start + sign * sweep
    if not h < 2 * r:
        raise MechanismError(f"/sections/{element.section}/h", f"width {h:g} is not below the arc's diameter {2 * r:g}")
    outer, inner = r + h / 2, r - h / 2

    def at(radius: float, angle: float) -> list[float]:
        return [cx + radius * math.cos(math.radians(angle)), cy + radius * math.sin(math.radians(angle))]

    bulge = math.tan(math.radians(sweep) / 4.0)
    points = np.array([at(outer, start), at(outer, end), at(inner, end), at(inner, start)])
    bulges = np.array([sign * bulge, 0.0, -sign * bulge, 0.0])
    low, high = (start, end) if sign > 0 else (end, start)
    arcs = [(cx, cy, outer, low, high), (cx, cy, inner, low, high)]
    return Outline("flexures", "curved_beam", base, points, bulges, True, arcs)


def _body_hulls(drawing: dict, widths: dict[str, float]) -> dict[str, tuple[np.ndarray, float, bool]]:
    """Per body: the convex hull of its reference point, skeleton and closed carried outlines, the
    margin it is grown by, and whether it is fixed."""
    carried: dict[str, list] = {}
    for outline in drawing["outlines"]:
        if outline.get("body") is not None and outline.get("closed"):
            carried.setdefault(outline["body"], []).extend(outline["points"])
    every = [p for e in drawing["elements"] for p in e["points"]] + [p for ps in carried.values() for p in ps]
    every += [b["reference"] for b in drawing["bodies"].values()]
    span = float(np.max(np.ptp(np.array(every), axis=0)))
    hulls = {}
    for body, data in drawing["bodies"].items():
        margin = max(MARGIN_WIDTHS * widths.get(body, 0.0), MARGIN_SPAN * span) or 1.0  # 1: a drawing of no size
        points = np.array([data["reference"], *data["skeleton"], *carried.get(body, [])])
        hulls[body] = (convex_hull(points), margin, data["fixed"])
    return hulls


def _deformed(mech: Mechanism) -> list[Outline]:
    from flexmech.service.solvers.equilibrium import solve_equilibrium

    state = solve_equilibrium(mech)
    if not state.converged:
        raise MechanismError("/deformed", f"the equilibrium under the document's loads did not solve: {state.status}")
    lines = mechanism_drawing(mech, state.z)["deformed"]["elements"]
    return [
        Outline("deformed", "deformed", f"/elements/{name}", np.array(line), np.zeros(len(line)), False)
        for name, line in lines.items()
    ]
