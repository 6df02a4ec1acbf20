"""The rigid joints of an impact model, each two rows of g(q, t) = 0 held by Lagrange
multipliers lambda:
- a pin keeps a point of its two bodies together (`at`, global in the drawn pose, default the
  `to` body's reference point); lambda is the force it applies to body `to` (Fx, Fy);
- a slider lets body `to` slide along an axis through `at` at `angle` (global, as drawn) that
  turns with body `from`, without turning relative to it (models.elements.slider):
  g = [n . (r_to(at) - r_from(at)), theta_to - theta_from], n the axis normal; lambda is the
  force along n it applies to `to` (N) and the couple that keeps `to` from turning (M)."""

from __future__ import annotations

import casadi as ca

from models.impacts.bodies import RigidBodies

JOINT_TYPES = ("pin", "slider")
LABELS = {"pin": (("Fx", "force"), ("Fy", "force")), "slider": (("N", "force"), ("M", "moment"))}


def joint_constraints(rb: RigidBodies) -> tuple[ca.SX, list[str], list[tuple]]:
    """(g stacked over the joints, their names, per joint its multipliers' (label, kind))."""
    rows, names, labels = [], [], []
    for name, element in rb.book.document.elements.items():
        if element.type not in JOINT_TYPES:
            continue
        base = f"/elements/{name}"
        first, second = rb.body(element.from_, f"{base}/from"), rb.body(element.to, f"{base}/to")
        at = rb.book.vector(f"{base}/at", element.at, "length") if element.at is not None else second.position
        apart = rb.drawn_point(second, at) - rb.drawn_point(first, at)
        if element.type == "pin":
            rows.append(apart)
        else:
            alpha = rb.book.number(f"{base}/angle", element.angle, "angle") + rb.rotation(first)
            normal = ca.vertcat(-ca.sin(alpha), ca.cos(alpha))
            rows.append(ca.vertcat(ca.dot(normal, apart), rb.rotation(second) - rb.rotation(first)))
        names.append(name)
        labels.append(LABELS[element.type])
    return (ca.vertcat(*rows) if rows else ca.SX(0, 1)), names, labels
