"""The drawing of a mechanism as data (document units), for the browser workbench: every
element's centre line (undeformed, and deformed at a solution, with the stress along it), the
bodies' reference points and skeletons, joints and springs, contact objects and impact surfaces
as outlines, loads as arrows, the units of the axes and stresses, and each element's allowable
stress (its material's stress_limit).

Whatever a body carries is drawn in its undeformed place and listed with the body's name; a
pose [dx, dy, rotation] moves it: p -> about + (dx, dy) + R(rotation) (p - about), `about`
being the body's reference point (statics, link dynamics) or its mass centre (impacts). One
transformation thus animates every kind of result.
"""

from __future__ import annotations

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.elements import FAMILIES
from flexmech.service.drawings.configuration_plot import load_point
from flexmech.service.drawings.outlines import circle_sites, contact_objects, document_length, in_body, turned
from flexmech.service.drawings.stresses import frame_stresses, stress_limits


def mechanism_drawing(mech: Mechanism, z: np.ndarray | None = None, outputs: dict | None = None) -> dict:
    """The drawing of `mech`; given a state z and its outputs (document units), also the
    deformed centre lines and every body's pose."""
    to_doc = 1.0 / mech.nd_per_doc("length")
    state = np.zeros(mech.structure.n_unknowns) if z is None else np.asarray(z, dtype=float)
    undeformed = np.asarray(mech.graphs.shapes(state, mech.p())[1], dtype=float) * to_doc
    bodies = _bodies(mech)
    elements = []
    for name, first, count, start, end in mech.graphs.shape_segments:
        points = undeformed[:, first : first + count].T
        ends = (mech.structure.bodies[start], mech.structure.bodies[end])
        for body, point in zip(ends, (points[0], points[-1])):
            bodies[body]["skeleton"].append(point.tolist())
        elements.append({"name": name, "from": ends[0], "to": ends[1], "points": points.tolist()})
    limits = stress_limits(mech)
    for element in elements:
        if element["name"] in limits:
            element["stress_limit"] = limits[element["name"]]
    drawing = {
        "name": mech.document.name,
        "units": {kind: mech.doc_unit(kind) for kind in ("length", "force", "moment", "angle", "stress")},
        "radians_per_angle_unit": mech.doc_factor("angle"),
        "bodies": bodies,
        "elements": elements,
        "connectors": _connectors(mech, bodies),
        "points": _point_outputs(mech, bodies),
        "loads": _loads(mech, bodies),
    }
    for point in drawing["points"]:  # a point output is on its body: joined to its reference point
        bodies[point["body"]]["skeleton"].append(point["point"])
    span = drawing_span(drawing)
    drawing["outlines"] = contact_objects(mech, bodies, span) + circle_sites(mech, bodies)
    if z is not None:
        drawing["deformed"] = state_frame(mech, state, mech.p(), outputs or {})
    return drawing


def state_frame(mech: Mechanism, z: np.ndarray, p: np.ndarray, outputs: dict) -> dict:
    """A state of the mechanism as the page animates it: every element's deformed centre
    line and every body's pose (document units; outputs of the state in document units); and,
    given its outputs, `stresses`: per beam element the outer-fibre bending stress at each point
    of its deformed line (the document's stress unit; service.drawings.stresses says which
    elements have them and how they are found)."""
    shapes = np.asarray(mech.graphs.shapes(z, p)[0], dtype=float)
    deformed = shapes / mech.nd_per_doc("length")
    frame = {
        "elements": {
            name: deformed[:, first : first + count].T.tolist()
            for name, first, count, _, _ in mech.graphs.shape_segments
        },
        "poses": poses_from_outputs(mech, outputs),
    }
    stresses = frame_stresses(mech, p, outputs, shapes)
    if stresses:
        frame["stresses"] = stresses
    return frame


def poses_from_outputs(mech: Mechanism, outputs: dict) -> dict[str, list[float]]:
    """Every body's pose [dx, dy, rotation in radians] about its reference point, from a
    solution's outputs bodies.<name>.x/y/angle (document units)."""
    poses = {}
    rad = mech.doc_factor("angle")
    for name in mech.structure.bodies:
        keys = [f"bodies.{name}.{c}" for c in ("x", "y", "angle")]
        if all(outputs.get(k) is not None for k in keys):
            x0, y0 = (mech.value(f"/bodies/{name}/position/{i}") for i in (0, 1))
            poses[name] = [
                outputs[keys[0]] - x0,
                outputs[keys[1]] - y0,
                (outputs[keys[2]] - _angle_of(mech, name)) * rad,
            ]
    return poses


def drawing_span(drawing: dict) -> float:
    """The largest extent of the bodies' and elements' points (document length units)."""
    points = [b["reference"] for b in drawing["bodies"].values()]
    points += [p for e in drawing["elements"] for p in e["points"]]
    if len(points) < 2:
        return 1.0
    extent = float(np.ptp(np.asarray(points, dtype=float), axis=0).max())
    return extent if extent > 0 else 1.0


def _angle_of(mech: Mechanism, body: str) -> float:
    try:
        return mech.value(f"/bodies/{body}/angle")
    except MechanismError:  # no angle field: drawn at 0
        return 0.0


def _bodies(mech: Mechanism) -> dict[str, dict]:
    """Per body: reference point, angle (radians), mass centre, fixed, and the points its
    skeleton joins to its reference point (filled in by the drawing)."""
    fixed = {
        mech.structure.bodies[b]: all(v is not None for v in row) for b, row in enumerate(mech.structure.prescribed)
    }
    bodies = {}
    for name, spec in mech.document.bodies.items():
        reference = np.array([mech.value(f"/bodies/{name}/position/{i}") for i in (0, 1)])
        angle = _angle_of(mech, name) * mech.doc_factor("angle")
        offset = getattr(spec, "center_of_mass", None)
        centre = (
            reference
            if offset is None
            else reference
            + turned(
                [document_length(mech, v, f"/bodies/{name}/center_of_mass/{i}") for i, v in enumerate(offset)], angle
            )
        )
        bodies[name] = {
            "reference": reference.tolist(),
            "angle": angle,
            "centre": centre.tolist(),
            "fixed": fixed.get(name, bool(getattr(spec, "fixed", False))),
            "skeleton": [],
        }
    return bodies


def _connectors(mech: Mechanism, bodies: dict) -> list[dict]:
    """Pins, sliders and springs: where they are (undeformed), on which bodies."""
    drawn = []
    for name, spec in mech.document.elements.items():
        ask = getattr(FAMILIES.named(spec.type), "connector", None)
        if ask is None:
            continue
        connector, pointer = ask(spec), f"/elements/{name}"
        points = []
        for field, body in connector.points:
            where = getattr(spec, field)
            points.append(
                bodies[body]["reference"]
                if where is None
                else [document_length(mech, v, f"{pointer}/{field}/{i}") for i, v in enumerate(where)]
            )
        entry = {
            "name": name,
            "type": spec.type,
            "glyph": connector.glyph,
            "bodies": [spec.from_, spec.to],
            "points": points,
        }
        if connector.angle_field is not None:
            entry["angle"] = float(mech.value(f"{pointer}/{connector.angle_field}")) * mech.doc_factor("angle")
        if connector.kind is not None:
            entry["kind"] = connector.kind
        drawn.append(entry)
    return drawn


def _point_outputs(mech: Mechanism, bodies: dict) -> list[dict]:
    """Point outputs where they are drawn (undeformed), on their bodies."""
    points = []
    for point in mech.structure.points:
        body = mech.structure.bodies[point.body]
        spec = mech.document.outputs[point.name]
        pointer = f"/outputs/{point.name}"
        at, offset = getattr(spec, "at", None), getattr(spec, "offset", None)
        if at is not None:
            where = np.array([document_length(mech, v, f"{pointer}/at/{i}") for i, v in enumerate(at)])
        else:
            where = in_body(
                bodies,
                body,
                [document_length(mech, v, f"{pointer}/offset/{i}") for i, v in enumerate(offset or (0, 0))],
            )
        points.append({"name": point.name, "body": body, "point": where.tolist()})
    return points


def _loads(mech: Mechanism, bodies: dict) -> list[dict]:
    """Forces (vector at their point) and moments (at the body's reference point), undeformed."""
    rest = {
        f"bodies.{name}.{c}": v
        for name, b in bodies.items()
        for c, v in zip(("x", "y", "angle"), (*b["reference"], b["angle"] / mech.doc_factor("angle")))
    }
    drawn = []
    for load in mech.structure.loads:
        body = mech.structure.bodies[load.body]
        entry = {
            "name": load.name,
            "kind": load.kind,
            "body": body,
            "point": load_point(mech, load.name, rest).tolist(),
        }
        if load.kind == "force":
            entry["vector"] = [mech.value(f"/loads/{load.name}/force/{i}") for i in (0, 1)]
        else:
            entry["value"] = mech.value(f"/loads/{load.name}/moment")
        drawn.append(entry)
    return drawn
