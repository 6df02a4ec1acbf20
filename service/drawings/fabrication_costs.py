"""What a fabrication drawing (service.drawings.fabrication) costs, counted before a vertex is
made: the GDS grid its coordinates need and the vertices of its outlines, arcs as GDS polygons.

An outline has at most MAX_OUTLINE_POINTS vertices (GDSII's most in one boundary: more would
split it in two) and a drawing MAX_POINTS. GDSII keeps coordinates as 32-bit integers of a grid
(its database unit): GRID of the length unit, or a tenth of the chord error when that is finer,
coarser (a power of ten) when the farthest coordinate would be more than MAX_GRID_STEPS steps
out. A chord error that would need more, or a grid coarser than a tenth of it, is refused at
/chord_error with the finest one that fits; arcs are cut to chords within the chord error less
the grid, so that every point of a polygon rounded to the grid stays within the chord error."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from flexmech.models import MechanismError
from flexmech.service.drawings.fabrication_geometry import arc_segments, bulge_arc, grown_hull_size

MAX_OUTLINE_POINTS = 8190  # GDSII's most vertices in one boundary
MAX_POINTS = 200_000  # vertices of a drawing, arcs as GDS polygons (about 12 MB of DXF at most)
GRID = 1e-6  # of the length unit
MAX_GRID_STEPS = 1e9  # the farthest coordinate in grid steps (GDSII's integers reach 2.1e9)
Hull = tuple[np.ndarray, float]  # a body's convex hull and the margin it is grown by


def grid_for(far: float, chord_error: float) -> float:
    """The GDS grid (length unit) for coordinates up to `far` from the origin."""
    grid = min(GRID, chord_error / 10)
    if far > MAX_GRID_STEPS * grid:
        grid = 10.0 ** math.ceil(math.log10(far) - math.log10(MAX_GRID_STEPS))
    return grid


def gds_grid(far: float, chord_error: float, unit: str) -> float:
    """grid_for, refused when it is coarser than a tenth of the chord error."""
    grid = grid_for(far, chord_error)
    if grid > chord_error / 10:
        raise MechanismError(
            "/chord_error",
            (
                f"{chord_error:g} {unit} is finer than GDSII holds {far:.3g} {unit} from the origin "
                f"(32-bit integers of a grid at most a tenth of the chord error): take at least {10 * grid:g} {unit}"
            ),
        )
    return grid


def gds_vertices(outline, tolerance: float) -> int:
    """The vertices of an outline (points, bulges) as a GDS polygon: its own and its arcs'."""
    n = len(outline.points)
    count = n
    for k in np.flatnonzero(outline.bulges):
        _, radius, _, theta = bulge_arc(outline.points[k], outline.points[(k + 1) % n], outline.bulges[k])
        count += max(2, arc_segments(radius, theta, tolerance)) - 1
    return count


def check_costs(outlines: list, hulls: list[Hull], chord_error: float, far: float, unit: str) -> None:
    """The outlines (curved beams, links) and the bodies' grown hulls, counted at this chord error:
    a MechanismError when one has more than MAX_OUTLINE_POINTS vertices or all more than MAX_POINTS."""
    for outline in outlines:
        if not outline.bulges.any() and len(outline.points) > MAX_OUTLINE_POINTS:  # a link: no chord error helps
            raise MechanismError(
                outline.pointer,
                (
                    f"its outline would have {len(outline.points)} vertices (both sides of its centre line's "
                    f"samples), more than GDSII's {MAX_OUTLINE_POINTS} in one boundary: give it fewer intervals"
                ),
            )

    def counts(ce: float) -> tuple[int, int]:
        tolerance = ce - grid_for(far, ce)
        sizes = [gds_vertices(o, tolerance) for o in outlines] + [
            grown_hull_size(len(h), m, tolerance) for h, m in hulls
        ]
        return max(sizes, default=0), sum(sizes)

    largest, total = counts(chord_error)
    if largest <= MAX_OUTLINE_POINTS and total <= MAX_POINTS:
        return
    where = (
        f"{largest} vertices in one outline, more than GDSII's {MAX_OUTLINE_POINTS} in a boundary"
        if largest > MAX_OUTLINE_POINTS
        else f"{total} vertices in all, more than {MAX_POINTS}"
    )
    enough = fitting(lambda ce: (lambda c: c[0] <= MAX_OUTLINE_POINTS and c[1] <= MAX_POINTS)(counts(ce)), chord_error)
    if enough is None:
        raise MechanismError("/elements", f"the outlines need {where} at any chord error: draw fewer or shorter links")
    raise MechanismError("/chord_error", f"{chord_error:g} {unit} needs {where}: take at least {enough:g} {unit}")


def fitting(fits: Callable[[float], bool], chord_error: float) -> float | None:
    """The smallest chord error above `chord_error` that fits, to two significant digits rounded
    up (bisection in its logarithm; the counts fall as it grows); None when none does."""
    low, high = chord_error, chord_error * 2
    while not fits(high):
        low, high = high, high * 4
        if high > 1e300:
            return None
    for _ in range(60):
        middle = math.sqrt(low * high)
        low, high = (low, middle) if fits(middle) else (middle, high)
    digits = math.floor(math.log10(high)) - 1
    shown = math.ceil(high / 10.0**digits) * 10.0**digits
    return float(f"{shown:.2g}") if fits(float(f"{shown:.2g}")) else shown * 1.1
