"""Plane geometry of fabrication drawings (service.drawings.fabrication), in one length unit:
how many chords an arc needs within a tolerance, the arc a DXF bulge stands for, and a convex
hull grown by a margin with round corners as polygons."""

from __future__ import annotations

import math

import numpy as np

QUARTER = math.pi / 2


def arc_segments(radius: float, angle: float, tolerance: float) -> int:
    """The fewest equal chords of an arc of `radius` turning by `angle` (rad) none of which lies
    farther than `tolerance` from it (a chord across s radians is 2 r sin^2(s/4) from its arc),
    and none across more than a quarter turn. Counted, never made: a caller costs its work first."""
    if radius <= 0:
        return 1
    ratio = tolerance / (2.0 * radius)
    step = min(QUARTER, 4.0 * math.asin(math.sqrt(ratio))) if ratio < 1 else QUARTER
    return max(1, math.ceil(abs(angle) / max(step, 1e-300) - 1e-9))


def bulge_arc(a: np.ndarray, b: np.ndarray, bulge: float) -> tuple[np.ndarray, float, float, float]:
    """(centre, radius, start angle, turn) of the arc from a to b of this DXF bulge (tan of a
    quarter of its included angle, positive counter-clockwise); angles in radians."""
    theta = 4.0 * math.atan(bulge)
    chord = float(np.hypot(*(b - a)))
    radius = chord / (2.0 * abs(math.sin(theta / 2.0)))
    normal = np.array([-(b - a)[1], (b - a)[0]]) / chord
    centre = (a + b) / 2.0 + normal * (chord / 2.0) / math.tan(theta / 2.0)
    return centre, radius, math.atan2(*(a - centre)[::-1]), theta


def arc_points(a: np.ndarray, b: np.ndarray, bulge: float, tolerance: float) -> list[np.ndarray]:
    """Points strictly between a and b on the arc of this bulge, so that no chord leaves the arc
    by more than tolerance."""
    centre, radius, start, theta = bulge_arc(a, b, bulge)
    count = max(2, arc_segments(radius, theta, tolerance))
    return [
        centre + radius * np.array([math.cos(start + theta * j / count), math.sin(start + theta * j / count)])
        for j in range(1, count)
    ]


def grown_hull(hull: np.ndarray, margin: float, tolerance: float) -> np.ndarray:
    """A convex hull (convex_hull's, (n, 2)) offset by `margin`, counter-clockwise: straight edges
    and round corners, each corner's vertices on its circle within `tolerance` of it (chords
    inside), with its points on the axis directions too, so the outline's extent is exactly
    the points' box grown by the margin. Its vertices number at most
    grown_hull_size(len(hull), margin, tolerance)."""
    n = len(hull)
    out = []
    for k in range(n):
        here = hull[k]
        if n == 1:
            a0, a1 = 0.0, 2 * math.pi
        else:
            a0, a1 = outward(hull[k - 1], here), outward(here, hull[(k + 1) % n])
            a1 = a1 if a1 >= a0 else a1 + 2 * math.pi
        angles = np.linspace(a0, a1, arc_segments(margin, a1 - a0, tolerance) + 1)
        axes = QUARTER * np.arange(math.ceil(a0 / QUARTER), math.floor(a1 / QUARTER) + 1)
        corner = np.unique(np.round(np.concatenate([angles, axes]), 12))
        if n == 1:  # a whole circle: its end is its start
            corner = corner[corner < a1 - 1e-12]
        out += [here + margin * np.array([math.cos(angle), math.sin(angle)]) for angle in corner]
    return np.array(out)


def grown_hull_size(corners: int, margin: float, tolerance: float) -> int:
    """An upper bound of grown_hull's vertices for a hull of `corners` points: the corners turn
    by a whole turn in all, each adds its ends and at most its axis directions."""
    return arc_segments(margin, 2 * math.pi, tolerance) + 2 * corners + 5


def outward(a: np.ndarray, b: np.ndarray) -> float:
    """The direction of the outward normal of the counter-clockwise edge a -> b."""
    d = b - a
    return math.atan2(-d[0], d[1])


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise hull (Andrew's monotone chain), duplicates and collinear points dropped."""
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
