"""The fabricated outline of a mechanism, for the shop (DXF) and the mask (GDS): every flexure and
link as the closed outline of its material, every body as a closed polygon, in the document's
length unit (service.drawings.fabrication_files writes them).

- A curved beam: two concentric arcs of radius r + h/2 and r - h/2 over its arc angle, joined at
  its ends by radial segments (the arcs are exact: DXF keeps them as arcs; GDS, which has none,
  takes polygons whose vertices lie on them, within the chord error).
- A link: its centre line offset by +-h/2 along its normals (h varying along a tapered section),
  closed across its ends; the centre line sampled as the drawing samples it, its largest chord
  deviation reported.
- A body: a document gives no body outline, so the drawing makes one: the convex hull of its
  reference point and the points its flexures, links and point outputs attach at, grown by
  MARGIN_WIDTHS times the widest section attached to it (at least MARGIN_SPAN of the drawing's
  extent); round corners as polygons within the chord error. A fixed body is on the anchors layer.
- Springs, pins and sliders are no material: they are not drawn.
The layers: bodies, flexures (curved beams and links), anchors, and deformed (the centre lines at
the equilibrium under the document's loads, when asked). Names in the document are never layer or
block names: they are data, and stay out of the files' structure."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.elements import FAMILIES
from flexmech.service.drawings.drawing import mechanism_drawing

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
    points: np.ndarray  # (n, 2)
    bulges: np.ndarray  # (n,)
    closed: bool = True
    arcs: list[tuple[float, float, float, float, float]] = field(default_factory=list)  # (cx, cy, r, from, to) deg


@dataclass
class Fabrication:
    unit: str
    chord_error: float
    outlines: list[Outline]
    link_chord_error: float  # the largest deviation of a link's sampled centre line from its chords

    def on(self, layer: str) -> list[Outline]:
        return [o for o in self.outlines if o.layer == layer]


def fabrication(mech: Mechanism, deformed: bool = False, chord_error: float = CHORD_ERROR) -> Fabrication:
    """The fabricated outlines of `mech` (its overrides applied); with `deformed`, also the centre
    lines at the equilibrium under the document's loads (MechanismError when it does not solve)."""
    if not chord_error > 0:
        raise MechanismError("/chord_error", f"must be positive, got {chord_error:g}")
    drawing = mechanism_drawing(mech)
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
            outline, deviation = _link(points_of[name], h0, h_end)
            outlines.append(outline)
            worst, h = max(worst, deviation), max(h0, h_end)
        else:
            continue
        for body in (element.from_, element.to):
            widths[body] = max(widths.get(body, 0.0), h)
    span = _span(drawing)
    for body, data in drawing["bodies"].items():
        margin = max(MARGIN_WIDTHS * widths.get(body, 0.0), MARGIN_SPAN * span)
        hull = [data["reference"], *data["skeleton"]]
        layer = "anchors" if data["fixed"] else "bodies"
        outlines.append(Outline(layer, "body", *_grown_hull(np.array(hull), margin, chord_error)))
    if deformed:
        outlines += _deformed(mech)
    return Fabrication(mech.doc_unit("length"), chord_error, outlines, worst)


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
    return Outline(
        "flexures", "curved_beam", points, bulges, True, [(cx, cy, outer, low, high), (cx, cy, inner, low, high)]
    )


def _link(points: np.ndarray, h0: float, h1: float) -> tuple[Outline, float]:
    """The centre line's samples offset by half the width (linear from h0 to h1 along the length)."""
    steps = np.diff(points, axis=0)
    lengths = np.hypot(*steps.T)
    along = np.concatenate([[0.0], np.cumsum(lengths)]) / max(lengths.sum(), 1e-300)
    tangents = np.zeros_like(points)
    tangents[:-1] += steps / lengths[:, None]
    tangents[1:] += steps / lengths[:, None]
    tangents /= np.hypot(*tangents.T)[:, None]
    normals = np.c_[-tangents[:, 1], tangents[:, 0]]
    half = 0.5 * (h0 + (h1 - h0) * along)[:, None]
    loop = np.vstack([points + half * normals, (points - half * normals)[::-1]])
    turns = np.abs(np.diff(np.unwrap(np.arctan2(steps[:, 1], steps[:, 0])))) if len(steps) > 1 else np.zeros(1)
    deviation = float(np.max(lengths[:-1] * turns / 8.0, initial=0.0))  # sagitta of a segment on a circle
    return Outline("flexures", "link", loop, np.zeros(len(loop))), deviation


def _grown_hull(points: np.ndarray, margin: float, chord_error: float) -> tuple[np.ndarray, np.ndarray]:
    """The convex hull of `points` offset by `margin`: straight edges and round corners, the
    corners as polygons whose chords stay within chord_error of the true circle."""
    hull = _convex_hull(points)
    step = 2 * math.acos(max(-1.0, 1 - chord_error / margin)) if chord_error < margin else math.pi / 2
    out = []
    n = len(hull)
    for k in range(n):
        before, here, after = hull[k - 1], hull[k], hull[(k + 1) % n]
        a0 = _outward(before, here) if n > 1 else 0.0
        a1 = _outward(here, after) if n > 1 else 2 * math.pi
        a1 = a1 if a1 >= a0 else a1 + 2 * math.pi
        count = max(1, math.ceil((a1 - a0) / step)) if n > 1 else max(8, math.ceil(2 * math.pi / step))
        angles = np.linspace(a0, a1, count + 1)[: None if n > 1 else -1]
        axes = np.pi / 2 * np.arange(math.ceil(a0 / (np.pi / 2)), math.floor(a1 / (np.pi / 2)) + 1)
        axes = axes[axes < a1 - 1e-12] if n == 1 else axes  # a whole circle: 2 pi is its start again
        for angle in np.unique(np.round(np.concatenate([angles, axes]), 12)):  # the axis directions too: an exact box
            out.append(here + margin * np.array([math.cos(angle), math.sin(angle)]))
    loop = np.array(out)
    return loop, np.zeros(len(loop))


def _outward(a: np.ndarray, b: np.ndarray) -> float:
    """The direction of the outward normal of the counter-clockwise edge a -> b."""
    d = b - a
    return math.atan2(-d[0], d[1])


def _convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise hull (Andrew's monotone chain), duplicates dropped."""
    unique = sorted({(round(float(x), 12), round(float(y), 12)) for x, y in points})
    if len(unique) <= 2:
        return np.array(unique)

    def half(sequence):
        chain: list = []
        for p in sequence:
            while len(chain) >= 2 and _cross(chain[-2], chain[-1], p) <= 0:
                chain.pop()
            chain.append(p)
        return chain

    lower, upper = half(unique), half(reversed(unique))
    return np.array(lower[:-1] + upper[:-1])


def _cross(o, a, b) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _span(drawing: dict) -> float:
    points = [p for e in drawing["elements"] for p in e["points"]] + [
        b["reference"] for b in drawing["bodies"].values()
    ]
    array = np.array(points)
    return float(np.max(array.max(axis=0) - array.min(axis=0))) if len(array) else 1.0


def _deformed(mech: Mechanism) -> list[Outline]:
    from flexmech.service.solvers.equilibrium import solve_equilibrium

    state = solve_equilibrium(mech)
    if not state.converged:
        raise MechanismError("/deformed", f"the equilibrium under the document's loads did not solve: {state.status}")
    lines = mechanism_drawing(mech, state.z)["deformed"]["elements"]
    return [Outline("deformed", "deformed", np.array(line), np.zeros(len(line)), False) for line in lines.values()]
