"""Where a contact can touch an element: the frames at its ends (for a rigid jaw carried by
the end section) and points along its centre line with their cross-section normals and half
thicknesses (for its surfaces), all symbolic in the element's unknowns."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca


@dataclass
class SurfacePoint:
    u: float  # along the element, 0..1
    centre: ca.SX  # (2,) on the centre line, global
    normal: ca.SX  # (2,) unit cross-section normal, to the left of the tangent
    half_thickness: ca.SX | None  # its surfaces lie that far either side; None: unknown
    weight: float = 0.0  # quadrature weight (du) of the point; 0 at the ends


@dataclass
class ElementSurfaces:
    frames: dict[str, tuple[ca.SX, ca.SX]]  # "start" | "end" -> (origin (2,), angle of the x axis)
    points: list[SurfacePoint]
