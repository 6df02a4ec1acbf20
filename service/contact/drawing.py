"""A contact state drawn as data (document length units), for the workbench's animation of
a contact path: each link's centre line and its two surfaces, each jaw's vertices, and each
object's outline where the state puts it. The pairs' forces and points are in the state's
pair report already."""

from __future__ import annotations

import numpy as np

from flexmech.models import Mechanism
from flexmech.service.contact.kkt import split
from flexmech.service.contact.problem import ContactProblem
from flexmech.service.contact.solve import ContactState
from flexmech.service.drawings.outlines import boundary_line, ellipse, turned

# A half-plane's boundary is drawn this many times the links' extent across.
HALF_PLANE_REACH = 3.0


def state_drawing(mech: Mechanism, problem: ContactProblem, state: ContactState) -> dict:
    to_doc = 1.0 / mech.nd_per_doc("length")
    w = split(problem, state.v).w
    jaws, links = (np.asarray(a, dtype=float) * to_doc for a in problem.drawing(w, state.p))
    drawn_links, start = [], 0
    for name, count in problem.drawn_links:
        block = links[:, start : start + 3 * count]
        start += 3 * count
        drawn_links.append(
            {
                "name": name,
                "centre": block[:, 0::3].T.tolist(),
                "left": block[:, 1::3].T.tolist(),
                "right": block[:, 2::3].T.tolist(),
            }
        )
    drawn_jaws, start = [], 0
    for name, count, closed in problem.drawn_jaws:
        drawn_jaws.append({"name": name, "points": jaws[:, start : start + count].T.tolist(), "closed": bool(closed)})
        start += count
    span = float(np.ptp(links, axis=1).max()) if links.size else 1.0
    return {"links": drawn_links, "jaws": drawn_jaws, "objects": _objects(mech, problem, w, state.p, span or 1.0)}


def _objects(mech: Mechanism, problem: ContactProblem, w, p, span: float) -> list[dict]:
    to_doc = 1.0 / mech.nd_per_doc("length")
    origins, angles = (np.asarray(a, dtype=float) for a in problem.frames(w, p))
    angles = angles.ravel()
    drawn = []
    for k, obj in enumerate(problem.structure.contacts.objects):
        origin = origins[:, k] * to_doc

        def value(field: str) -> float:
            return float(p[mech.parameter_index(f"{obj.pointer}/{field}")])

        if obj.type in ("circle", "hole"):
            points, closed = ellipse(origin, value("radius") * to_doc, value("radius") * to_doc), True
        elif obj.type == "ellipse":
            points = ellipse(origin, value("semi_axes/0") * to_doc, value("semi_axes/1") * to_doc, angles[k])
            closed = True
        elif obj.type == "polygon":
            count = 1 + max(max(piece) for piece in obj.pieces)
            local = [[value(f"vertices/{i}/0") * to_doc, value(f"vertices/{i}/1") * to_doc] for i in range(count)]
            points = [(origin + turned(vertex, angles[k])).tolist() for vertex in local + local[:1]]
            closed = True
        elif obj.type == "half_plane":
            normal = turned([value("normal/0"), value("normal/1")], angles[k])
            points, closed = boundary_line(origin, normal, HALF_PLANE_REACH * span), False
        else:
            continue  # an implicit object: a level set, not drawn
        drawn.append({"name": obj.name, "type": obj.type, "points": points, "closed": closed})
    return drawn
