"""The pins of an impact model: each keeps a point of its two bodies together, g(q, t) = 0
(2 rows; `at`, global in the drawn pose, default the `to` body's reference point). The
multipliers lambda are the force the pin applies to body `to` (models.elements.pin's Fx, Fy)."""

from __future__ import annotations

import casadi as ca

from models.impacts.bodies import RigidBodies


def pin_constraints(rb: RigidBodies) -> tuple[ca.SX, list[str]]:
    """(g stacked over the pins, their names)."""
    rows, names = [], []
    for name, element in rb.book.document.elements.items():
        if element.type != "pin":
            continue
        base = f"/elements/{name}"
        first, second = rb.body(element.from_, f"{base}/from"), rb.body(element.to, f"{base}/to")
        at = rb.book.vector(f"{base}/at", element.at, "length") if element.at is not None else second.position
        rows.append(rb.drawn_point(second, at) - rb.drawn_point(first, at))
        names.append(name)
    return (ca.vertcat(*rows) if rows else ca.SX(0, 1)), names
