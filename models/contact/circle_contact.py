"""A circle (centre O1, radius R1) against an object, placed in global coordinates: the
indentation q (positive in contact; the gap is -q) and the contact normal n_c (pushing the
circle out of contact). The impact model (models.impacts.pairs) and the elastic pairs of the
statics and link dynamics (models.contact.elastic_pairs) place the object each in their own
numbers and share these.

Polygons (convex or not) and ellipses are measured from their nearest boundary point, so the
circle's centre must stay outside them."""

from __future__ import annotations

import casadi as ca

ELLIPSE_BISECTIONS = 80  # halvings of the foot point's bracket: to round-off from any start
ELLIPSE_NEWTON = 2  # Newton steps after them, so that derivatives are the implicit function's


def against_circle(O1, R1, O2, R2) -> tuple[ca.SX, ca.SX]:
    e = O1 - O2
    distance = ca.sqrt(ca.dot(e, e) + 1e-300)
    return R1 + R2 - distance, e / distance


def against_hole(O1, R1, O2, R2) -> tuple[ca.SX, ca.SX]:
    """A circle inside a circular hole of radius R2 (the solid outside it)."""
    e = O1 - O2
    distance = ca.sqrt(ca.dot(e, e) + 1e-300)
    return distance - (R2 - R1), -e / distance


def against_half_plane(O1, R1, P2, n_c) -> tuple[ca.SX, ca.SX]:
    """The solid behind the line through P2 with unit normal n_c pointing out of it."""
    return R1 - ca.dot(O1 - P2, n_c), n_c


def against_nearest(O1, R1, closest) -> tuple[ca.SX, ca.SX]:
    """Against an object whose boundary point nearest O1 is `closest`."""
    e = O1 - closest
    distance = ca.sqrt(ca.dot(e, e) + 1e-300)
    return R1 - distance, e / distance


def closest_on_polygon(corners: list, O1) -> ca.SX:
    """The point of the polygon's boundary (corners in order, edges closed) nearest O1: the
    nearest of each edge's nearest points."""
    best, best_squared = None, None
    for A, B in zip(corners, corners[1:] + corners[:1]):
        edge = B - A
        along = ca.fmin(ca.fmax(ca.dot(O1 - A, edge) / ca.dot(edge, edge), 0), 1)
        nearest = A + along * edge
        squared = ca.sumsqr(O1 - nearest)
        if best is None:
            best, best_squared = nearest, squared
        else:
            closer = squared < best_squared
            best, best_squared = ca.if_else(closer, nearest, best), ca.if_else(closer, squared, best_squared)
    return best


def closest_on_ellipse(centre, turn, a, b, O1) -> ca.SX:
    """The point of the ellipse (semi-axes a, b along the columns of the rotation `turn`)
    nearest O1, outside it. In the ellipse's axes, O1 at p and the boundary at (a cos t,
    b sin t): the foot point's t solves f(t) = (a^2 - b^2) sin t cos t - a p_x sin t + b p_y
    cos t = 0. Bisection of Eberly's bracket in the first quadrant finds it from anywhere (the
    larger semi-axis first); Newton steps on f then give the derivatives of t that the
    implicit function theorem gives."""
    p = turn.T @ (O1 - centre)
    swapped = a < b  # Eberly's bracket wants the larger semi-axis first
    e0, e1 = ca.if_else(swapped, b, a), ca.if_else(swapped, a, b)
    y0 = ca.fabs(ca.if_else(swapped, p[1], p[0]))
    y1 = ca.fabs(ca.if_else(swapped, p[0], p[1]))
    r0, z0, z1 = (e0 / e1) ** 2, y0 / e0, y1 / e1
    low, high = z1 - 1, ca.sqrt((r0 * z0) ** 2 + z1**2) - 1
    for _ in range(ELLIPSE_BISECTIONS):
        s = (low + high) / 2
        outside = (r0 * z0 / (s + r0)) ** 2 + (z1 / (s + 1)) ** 2 - 1 > 0
        low, high = ca.if_else(outside, s, low), ca.if_else(outside, high, s)
    s = (low + high) / 2
    x0, x1 = r0 * y0 / (s + r0), y1 / (s + 1)  # the foot point in the first quadrant, (e0, e1) axes
    u0 = ca.if_else(swapped, x1 * ca.sign(p[0]), x0 * ca.sign(p[0]))
    u1 = ca.if_else(swapped, x0 * ca.sign(p[1]), x1 * ca.sign(p[1]))
    t = ca.atan2(u1 / b, u0 / a)
    for _ in range(ELLIPSE_NEWTON):
        f = (a**2 - b**2) * ca.sin(t) * ca.cos(t) - a * p[0] * ca.sin(t) + b * p[1] * ca.cos(t)
        slope = (a**2 - b**2) * ca.cos(2 * t) - a * p[0] * ca.cos(t) - b * p[1] * ca.sin(t)
        t = t - f / slope
    return centre + turn @ ca.vertcat(a * ca.cos(t), b * ca.sin(t))
