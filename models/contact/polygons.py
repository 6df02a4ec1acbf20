"""Plane polygons, numerically (document values, at compile time): whether a polygon is
simple, and its split into convex pieces (the non-penetration constraints separate convex
pieces by a line)."""

from __future__ import annotations

import numpy as np


def _cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def _segments_cross(p1, p2, q1, q2) -> bool:
    """Whether two closed segments share a point."""
    d1, d2 = _cross(q1, q2, p1), _cross(q1, q2, p2)
    d3, d4 = _cross(p1, p2, q1), _cross(p1, p2, q2)
    if ((d1 > 0) != (d2 > 0)) and ((d3 > 0) != (d4 > 0)) and d1 * d2 != 0 and d3 * d4 != 0:
        return True

    def on(a, b, c, d):  # c on segment ab, given collinear (d == 0)
        return d == 0 and min(a[0], b[0]) <= c[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= c[1] <= max(a[1], b[1])

    return on(q1, q2, p1, d1) or on(q1, q2, p2, d2) or on(p1, p2, q1, d3) or on(p1, p2, q2, d4)


def self_intersection(vertices: np.ndarray) -> tuple[int, int] | None:
    """The first two edges (i from vertex i to i + 1) of a closed polygon that cross or touch
    (other than neighbours at their shared vertex), or None for a simple polygon."""
    n = len(vertices)
    for i in range(n):
        for j in range(i + 1, n):
            if j == i + 1 or (i == 0 and j == n - 1):
                continue
            if _segments_cross(vertices[i], vertices[(i + 1) % n], vertices[j], vertices[(j + 1) % n]):
                return i, j
    return None


def signed_area(vertices: np.ndarray) -> float:
    x, y = vertices[:, 0], vertices[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def is_convex(vertices: np.ndarray) -> bool:
    n = len(vertices)
    turns = [_cross(vertices[i], vertices[(i + 1) % n], vertices[(i + 2) % n]) for i in range(n)]
    return all(t >= 0 for t in turns) or all(t <= 0 for t in turns)


def convex_pieces(vertices: np.ndarray) -> tuple[tuple[int, ...], ...]:
    """A simple polygon as convex pieces (vertex indices): itself if convex, else the
    triangles of an ear-clipping triangulation."""
    n = len(vertices)
    if is_convex(vertices):
        return (tuple(range(n)),)
    order = list(range(n)) if signed_area(vertices) > 0 else list(range(n))[::-1]
    triangles = []
    while len(order) > 3:
        for k in range(len(order)):
            a, b, c = order[k - 1], order[k], order[(k + 1) % len(order)]
            if _cross(vertices[a], vertices[b], vertices[c]) <= 0:
                continue  # a reflex corner is no ear
            inside = any(
                _inside_triangle(vertices[m], vertices[a], vertices[b], vertices[c])
                for m in order
                if m not in (a, b, c)
            )
            if not inside:
                triangles.append((a, b, c))
                order.pop(k)
                break
        else:  # rounding on a degenerate polygon: stop clipping
            break
    triangles.append(tuple(order))
    return tuple(triangles)


def _inside_triangle(point, a, b, c) -> bool:
    return _cross(a, b, point) >= 0 and _cross(b, c, point) >= 0 and _cross(c, a, point) >= 0
