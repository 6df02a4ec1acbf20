"""The rigid joints of an impact model, each two rows of g(q, t) = 0 held by Lagrange
multipliers lambda: every element family with `impact_constraint` (models.elements: a pin
keeps a point of its two bodies together, lambda its force on `to`; a slider lets `to` slide
along an axis of `from` without turning, lambda its force across the axis and its couple)."""

from __future__ import annotations

import casadi as ca

from models.elements import FAMILIES
from models.impacts.bodies import RigidBodies


def joint_constraints(rb: RigidBodies) -> tuple[ca.SX, list[str], list[tuple]]:
    """(g stacked over the joints, their names, per joint its multipliers' (label, kind))."""
    rows, names, labels = [], [], []
    for name, element in rb.book.document.elements.items():
        family = FAMILIES.named(element.type)
        if not hasattr(family, "impact_constraint"):
            continue
        g, named = family.impact_constraint(rb, name, element)
        rows.append(g)
        names.append(name)
        labels.append(named)
    return (ca.vertcat(*rows) if rows else ca.SX(0, 1)), names, labels
