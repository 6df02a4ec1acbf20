"""A link's fabricated outline (service.drawings.fabrication): its centre line offset by half its
width on either side, cut to chords within the chord error.

The drawing samples a link's centre line (service.drawings.drawing: four points per shooting
interval); between the samples the line is a cubic spline in its chord length through them, exact
for a straight link, and for a curved one off the true line by a distance that falls with the
fourth power of the samples' spacing (interpolation_error estimates it). Each interval is cut
into as many equal pieces as keep every chord of either offset within the tolerance of the
spline: a piece of length l where the curvature reaches k lies l^2 k (1 + k h/2) / 8 from its arc."""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline

from flexmech.models import MechanismError
from flexmech.service.drawings.fabrication_costs import MAX_OUTLINE_POINTS, fitting


def link_outline(points: np.ndarray, h0: float, h1: float, chord_error: float, unit: str, pointer: str) -> np.ndarray:
    """The closed outline (2n, 2) of a link whose centre line passes through `points` (n, 2),
    width h0 at its start and h1 at its end (linear along it): one side from start to end, the
    other back, its chords within 0.9 of the chord error of the spline (the rest is the GDS
    grid's). A MechanismError when it would have more than MAX_OUTLINE_POINTS vertices: at
    /chord_error with one that fits, or at the element when its samples alone are too many."""
    spline, t = _spline(points, pointer)
    if 2 * len(t) > MAX_OUTLINE_POINTS:
        raise MechanismError(
            pointer,
            (
                f"its outline would have at least {2 * len(t)} vertices (both sides of its centre line's samples), "
                f"more than GDSII's {MAX_OUTLINE_POINTS} in one boundary: give it fewer intervals"
            ),
        )
    sagitta = _sagitta(spline, t, max(h0, h1))

    def vertices(ce: float) -> int:
        return 2 * (int(_pieces(sagitta, 0.9 * ce).sum()) + 1)

    if vertices(chord_error) > MAX_OUTLINE_POINTS:
        enough = fitting(lambda ce: vertices(ce) <= MAX_OUTLINE_POINTS, chord_error)
        raise MechanismError(
            "/chord_error",
            (
                f"{chord_error:g} {unit} needs {vertices(chord_error)} vertices in a link's outline, more than "
                f"GDSII's {MAX_OUTLINE_POINTS} in a boundary: take at least {enough:g} {unit}"
            ),
        )
    pieces = _pieces(sagitta, 0.9 * chord_error)
    u = np.concatenate([np.linspace(a, b, int(m), endpoint=False) for a, b, m in zip(t[:-1], t[1:], pieces)] + [t[-1:]])
    centre, tangent = spline(u), spline(u, 1)
    tangent /= np.hypot(*tangent.T)[:, None]
    normal = np.c_[-tangent[:, 1], tangent[:, 0]]
    half = 0.5 * (h0 + (h1 - h0) * u / t[-1])[:, None]
    return np.vstack([centre + half * normal, (centre - half * normal)[::-1]])


def interpolation_error(points: np.ndarray, pointer: str) -> float:
    """An estimate of how far the spline through `points` leaves the true centre line: the spline
    through every other sample misses the others by about 16 times as much (fourth order)."""
    spline, t = _spline(points, pointer)
    if len(t) < 5:
        return 0.0
    kept = list(range(0, len(t), 2)) + ([len(t) - 1] if len(t) % 2 == 0 else [])
    left = np.setdiff1d(np.arange(len(t)), kept)
    coarse = CubicSpline(t[kept], spline(t[kept]), axis=0)
    return float(np.hypot(*(coarse(t[left]) - spline(t[left])).T).max()) / 16.0


def _spline(points: np.ndarray, pointer: str) -> tuple[CubicSpline, np.ndarray]:
    steps = np.hypot(*np.diff(points, axis=0).T)
    keep = np.concatenate([[True], steps > 0])  # a repeated sample adds nothing
    points, t = points[keep], np.concatenate([[0.0], np.cumsum(steps[steps > 0])])
    if len(t) < 2:
        raise MechanismError(pointer, "its centre line has no length to draw")
    return CubicSpline(t, points, axis=0), t


def _sagitta(spline: CubicSpline, t: np.ndarray, h: float) -> np.ndarray:
    """Per interval of t: how far its chord would lie from the outer offset of the spline."""
    ends = np.concatenate([t, (t[:-1] + t[1:]) / 2])
    d1, d2 = spline(ends, 1), spline(ends, 2)
    kappa = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / np.hypot(*d1.T) ** 3
    n = len(t) - 1
    k = np.maximum.reduce([kappa[:n], kappa[1 : n + 1], kappa[n + 1 :]])  # start, end, middle of each
    return np.diff(t) ** 2 * k * (1 + k * h / 2) / 8


def _pieces(sagitta: np.ndarray, tolerance: float) -> np.ndarray:
    """Equal pieces per interval: a piece of 1/m of it lies 1/m^2 as far from its arc."""
    return np.maximum(1, np.ceil(np.sqrt(np.minimum(sagitta / tolerance, 1e12))))
