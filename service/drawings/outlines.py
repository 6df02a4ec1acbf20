"""Outlines of the drawing (service.drawings.drawing): contact objects (circle, hole, ellipse, polygon,
half-plane) and circle sites as closed or open polylines, globally in
the undeformed configuration (document length units), with the body that carries them."""

from __future__ import annotations

import math

import numpy as np

from flexmech.models import Mechanism
from flexmech.models.units import quantity_to_si

CIRCLE_SAMPLES = 72
# A half-plane or a line surface is drawn across this multiple of the drawing's span.
LINE_SPAN = 1.5


def document_length(mech: Mechanism, value, pointer: str) -> float:
    """A length of the document (a number in its unit, or a quantity string), in its unit."""
    return quantity_to_si(value, "length", mech.doc_unit("length"), pointer) / mech.doc_factor("length")


def document_angle(mech: Mechanism, value, pointer: str) -> float:
    """An angle of the document, in radians."""
    return quantity_to_si(value, "angle", mech.doc_unit("angle"), pointer)


def turned(vector, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([c * vector[0] - s * vector[1], s * vector[0] + c * vector[1]])


def in_body(bodies: dict, body: str, local) -> np.ndarray:
    """A point given in a body's axes (from its reference point), globally, undeformed."""
    return np.asarray(bodies[body]["reference"]) + turned(local, bodies[body]["angle"])


def ellipse(centre, a: float, b: float, angle: float = 0.0) -> list[list[float]]:
    """A closed polyline (the first point repeated) of an ellipse of semi-axes a, b."""
    t = np.linspace(0.0, 2.0 * math.pi, CIRCLE_SAMPLES + 1)
    local = np.vstack([a * np.cos(t), b * np.sin(t)])
    c, s = math.cos(angle), math.sin(angle)
    return (np.asarray(centre, dtype=float)[:, None] + np.array([[c, -s], [s, c]]) @ local).T.tolist()


def boundary_line(point, normal, span: float) -> list[list[float]]:
    """The line through `point` across LINE_SPAN x span, perpendicular to `normal`."""
    n = np.asarray(normal, dtype=float)
    n = n / (np.hypot(*n) or 1.0)
    along = np.array([-n[1], n[0]]) * LINE_SPAN * span / 2
    return [(np.asarray(point) - along).tolist(), (np.asarray(point) + along).tolist()]


def contact_objects(mech: Mechanism, bodies: dict, span: float) -> list[dict]:
    contacts = getattr(mech.document, "contacts", None)
    if contacts is None:
        return []
    drawn = []
    for name, obj in contacts.objects.items():
        pointer = f"/contacts/objects/{name}"

        def length(field: str, value) -> float:
            return document_length(mech, value, f"{pointer}/{field}")

        local = _object_outline(obj, length, lambda v, f: document_angle(mech, v, f"{pointer}/{f}"), span)
        if local is None:
            continue
        points, closed = local
        if obj.body is not None:  # the pose is in the body's axes
            points = [in_body(bodies, obj.body, p).tolist() for p in points]
        drawn.append(
            {
                "name": name,
                "kind": "object",
                "type": obj.type,
                "body": obj.body,
                "points": points,
                "closed": closed,
                "solid": obj.type != "hole",
                **({"normal": _normal_of(obj, bodies)} if obj.type == "half_plane" else {}),
            }
        )
    return drawn


def _object_outline(obj, length, angle, span: float):
    """(points in the object's frame of reference, closed), or None for an object not drawn."""
    if obj.type in ("circle", "hole"):
        r = length("radius", obj.radius)
        return ellipse([length(f"centre/{i}", v) for i, v in enumerate(obj.centre)], r, r), True
    if obj.type == "ellipse":
        centre = [length(f"centre/{i}", v) for i, v in enumerate(obj.centre)]
        a, b = (length(f"semi_axes/{i}", v) for i, v in enumerate(obj.semi_axes))
        return ellipse(centre, a, b, angle(obj.angle, "angle")), True
    if obj.type == "polygon":
        position = np.array([length(f"position/{i}", v) for i, v in enumerate(obj.position)])
        turn = angle(obj.angle, "angle") if hasattr(obj, "angle") else 0.0
        points = [
            (position + turned([length(f"vertices/{k}/{i}", v) for i, v in enumerate(vertex)], turn)).tolist()
            for k, vertex in enumerate(obj.vertices)
        ]
        return points + points[:1], True
    if obj.type == "half_plane":
        point = [length(f"point/{i}", v) for i, v in enumerate(obj.point)]
        return boundary_line(point, [float(v) for v in obj.normal], span), False
    return None  # an implicit object: its outline is a level set, not drawn


def _normal_of(obj, bodies: dict) -> list[float]:
    normal = [float(v) for v in obj.normal]
    return turned(normal, bodies[obj.body]["angle"]).tolist() if obj.body is not None else normal


def circle_sites(mech: Mechanism, bodies: dict) -> list[dict]:
    """The circle sites of `contacts` (pins, rollers), solid, on their bodies."""
    contacts = getattr(mech.document, "contacts", None)
    if contacts is None:
        return []
    drawn = []
    for name, site in contacts.sites.items():
        if site.type != "circle":
            continue
        pointer = f"/contacts/sites/{name}"
        centre = in_body(
            bodies, site.body, [document_length(mech, v, f"{pointer}/centre/{i}") for i, v in enumerate(site.centre)]
        )
        r = document_length(mech, site.radius, f"{pointer}/radius")
        drawn.append(
            {
                "name": name,
                "kind": "site",
                "type": "circle",
                "body": site.body,
                "points": ellipse(centre, r, r),
                "closed": True,
                "solid": True,
            }
        )
    return drawn
