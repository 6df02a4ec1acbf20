"""The non-penetration constraints of every contact pair, as rows h(x, a, p) >= 0 of the
contact problem (x the energy form's unknowns, a the separating axes' variables).

Each row that pushes on the site names the site's material point P it acts at and dh/dP,
so its multiplier lam gives the force lam dh/dP on the site there (the contact force), and
a friction force can act at the same material point.

Two kinds of rows:
- pointwise, h(P) >= 0 at points of the site: a link surface's points (its ends and every
  quadrature point) against a circle, an ellipse, a half-plane or an implicit curve, and a
  jaw's vertices against a half-plane (exact), single-vertex jaws against circles and
  ellipses (exact), a jaw's edges sampled against an implicit curve (SAMPLES_PER_EDGE);
- a separating axis between convex pieces (exact): a line with unit normal n(theta) and
  offset c, the jaw piece's vertices behind it (c - n.v >= 0) and the object in front
  (circle n.centre - R - c >= 0, ellipse n.centre - sqrt(a^2 (n.e1)^2 + b^2 (n.e2)^2) - c
  >= 0, polygon n.w - c >= 0 per vertex). The contact force then acts at the jaw's vertices,
  split so that its resultant passes through the true contact point, wherever along an edge
  that is.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

from flexmech.models.contact.topology import ContactTopology, ObjectTopology, SiteTopology
from flexmech.models.documents.expression import compile_expression
from flexmech.models.errors import MechanismError
from flexmech.models.graph.planar import rot

SAMPLES_PER_EDGE = 8  # points per jaw edge checked against an implicit curve
QUASI_STATIC_CIRCLE_TOUCHES = ("circle", "hole", "half_plane")  # distances exact here


@dataclass
class ContactRow:
    pair: int
    value: ca.SX  # h >= 0
    point: ca.SX | None = None  # (2,) the site's material point the row pushes (None: an object's row)
    normal: ca.SX | None = None  # (2,) dh/dP at that point
    site_parameter: ca.SX | None = None  # where along the site (nondimensional length)
    axis: int = -1  # the separating axis the row belongs to (-1: a pointwise row)
    carrier: str | None = None  # the link whose points it pushes (a surface, a jaw on a link's end), or None


@dataclass
class ObjectFrame:
    origin: ca.SX  # (2,)
    angle: ca.SX


@dataclass
class ContactConstraints:
    axes: ca.SX  # (theta, c) of every separating axis
    axes_guess: ca.SX  # a separating line at the state the expressions are of (for starting)
    axis_pairs: list[int]  # the pair of each axis
    rows: list[ContactRow]
    object_frames: list[ObjectFrame] = field(default_factory=list)  # per object: its rigid motion
    pair_objects: list[int] = field(default_factory=list)  # per pair, its object


class ContactGeometry:
    """The symbolic geometry of objects and sites for body displacements d and the elements'
    surfaces (models.graph.forms.SymbolicEnergy)."""

    def __init__(self, ctx, d: list[ca.SX], surfaces: dict, topology: ContactTopology):
        self.ctx, self.P, self.d, self.surfaces, self.topology = ctx, ctx.P, d, surfaces, topology

    # objects -----------------------------------------------------------------------------------
    def object_frame(self, obj: ObjectTopology) -> ObjectFrame:
        base, P = obj.pointer, self.P
        origin_field = {"circle": "centre", "hole": "centre", "ellipse": "centre", "half_plane": "point"}.get(
            obj.type, "position"
        )
        local = P.vec(f"{base}/{origin_field}")
        own_angle = P[f"{base}/angle"] if obj.type in ("ellipse", "polygon", "implicit") else ca.SX(0)
        if obj.body is None:
            return ObjectFrame(local, own_angle)
        body_angle = self.ctx.reference(obj.body)[1] + self.d[obj.body][2]
        return ObjectFrame(self.ctx.place(obj.body, local, self.d), body_angle + own_angle)

    def _object_vertices(self, obj: ObjectTopology, frame: ObjectFrame) -> list[ca.SX]:
        count = 1 + max(max(piece) for piece in obj.pieces)
        return [frame.origin + rot(frame.angle) @ self.P.vec(f"{obj.pointer}/vertices/{k}") for k in range(count)]

    def _half_plane_normal(self, obj: ObjectTopology, frame: ObjectFrame) -> ca.SX:
        m = rot(frame.angle) @ self.P.vec(f"{obj.pointer}/normal")
        return m / ca.norm_2(m)

    def pointwise(self, obj: ObjectTopology, frame: ObjectFrame, point: ca.SX) -> ca.SX:
        """h(point) >= 0 outside the object; |dh/dpoint| = 1 on its boundary (a distance to
        first order; for an ellipse, scaled by the root of its semi-axes' product)."""
        base, P = obj.pointer, self.P
        if obj.type == "circle":
            return ca.norm_2(point - frame.origin) - P[f"{base}/radius"]
        if obj.type == "hole":  # smooth where a pin sits centred (no normal there, and no contact)
            return P[f"{base}/radius"] - ca.sqrt(ca.sumsqr(point - frame.origin) + 1e-24)
        if obj.type == "half_plane":
            return ca.dot(self._half_plane_normal(obj, frame), point - frame.origin)
        local = rot(frame.angle).T @ (point - frame.origin)
        if obj.type == "ellipse":
            a, b = P[f"{base}/semi_axes/0"], P[f"{base}/semi_axes/1"]
            return (ca.sqrt((local[0] / a) ** 2 + (local[1] / b) ** 2) - 1) * ca.sqrt(a * b)
        unit = self.ctx.unit("length")  # implicit: g in document length units
        build = compile_expression(obj.expression, f"{base}/expression", variable="x", names=("y",))
        probe = ca.SX.sym("probe", 2)
        g = ca.SX(build(probe[0] / unit, {"y": probe[1] / unit}))
        slope = ca.gradient(g, probe)
        value = g / ca.norm_2(slope)
        return ca.substitute(value, probe, local)

    def support(self, obj: ObjectTopology, frame: ObjectFrame, n: ca.SX, piece: tuple[int, ...]) -> list[ca.SX]:
        """The object's (piece's) extent along n: rows n.y - c needs each >= c (as offsets)."""
        base, P = obj.pointer, self.P
        if obj.type == "circle":
            return [ca.dot(n, frame.origin) - P[f"{base}/radius"]]
        if obj.type == "ellipse":
            a, b = P[f"{base}/semi_axes/0"], P[f"{base}/semi_axes/1"]
            e1 = ca.vertcat(ca.cos(frame.angle), ca.sin(frame.angle))
            e2 = ca.vertcat(-ca.sin(frame.angle), ca.cos(frame.angle))
            return [ca.dot(n, frame.origin) - ca.sqrt((a * ca.dot(n, e1)) ** 2 + (b * ca.dot(n, e2)) ** 2)]
        vertices = self._object_vertices(obj, frame)
        return [ca.dot(n, vertices[k]) for k in piece]

    def centre(self, obj: ObjectTopology, frame: ObjectFrame, piece: tuple[int, ...]) -> ca.SX:
        if obj.type == "polygon":
            vertices = self._object_vertices(obj, frame)
            return sum((vertices[k] for k in piece), ca.SX.zeros(2)) / len(piece)
        return frame.origin

    # sites -------------------------------------------------------------------------------------
    def site_frame(self, site: SiteTopology) -> tuple[ca.SX, ca.SX]:
        if site.body is not None:
            r, angle = self.ctx.reference(site.body)
            return r + self.d[site.body][:2], angle + self.d[site.body][2]
        return self.surfaces[site.link].frames[site.end]

    def jaw_vertices(self, site: SiteTopology) -> tuple[list[ca.SX], list[ca.SX]]:
        """World positions of the jaw's vertices, and each one's arc length along the jaw."""
        origin, angle = self.site_frame(site)
        local = [self.P.vec(f"{site.pointer}/vertices/{k}") for k in range(site.n_vertices)]
        along, total = [], ca.SX(0)
        for k in range(site.n_vertices):
            if k:
                total = total + ca.norm_2(local[k] - local[k - 1])
            along.append(total)
        return [origin + rot(angle) @ v for v in local], along

    def surface_points(self, site: SiteTopology) -> list[tuple[ca.SX, ca.SX]]:
        """(material point, arc length from the link's start) of every checked surface point."""
        sign = {"left": 1.0, "right": -1.0, "centre_line": 0.0}[site.side]
        length = self.P[f"/elements/{site.link}/length"]
        out = []
        for point in self.surfaces[site.link].points:
            offset = sign * point.half_thickness * point.normal if sign else ca.SX.zeros(2)
            out.append((point.centre + offset, point.u * length))
        return out


def substituted(constraints: ContactConstraints, old: ca.SX, new: ca.SX) -> ContactConstraints:
    """The same constraints with `old` replaced by `new` in every expression."""

    def fix(e):
        return None if e is None else ca.substitute(e, old, new)

    rows = [
        ContactRow(r.pair, fix(r.value), fix(r.point), fix(r.normal), fix(r.site_parameter), r.axis, r.carrier)
        for r in constraints.rows
    ]
    frames = [ObjectFrame(fix(f.origin), fix(f.angle)) for f in constraints.object_frames]
    return ContactConstraints(
        constraints.axes, fix(constraints.axes_guess), constraints.axis_pairs, rows, frames, constraints.pair_objects
    )


def contact_constraints(geometry: ContactGeometry) -> ContactConstraints:
    topology = geometry.topology
    frames = [geometry.object_frame(obj) for obj in topology.objects]
    rows, axes, guesses, axis_pairs = [], [], [], []
    for k, pair in enumerate(topology.pairs):
        site, obj = topology.sites[pair.site], topology.objects[pair.object]
        frame = frames[pair.object]
        first = len(rows)
        if site.type == "surface":
            rows += [
                _pointwise_row(geometry, k, obj, frame, point, along) for point, along in geometry.surface_points(site)
            ]
            _carried(rows, first, site.link)
            continue
        if site.type == "circle":
            if obj.type not in QUASI_STATIC_CIRCLE_TOUCHES:
                raise MechanismError(
                    f"{pair.pointer}/object",
                    f"a quasi-static contact solve takes a circle site "
                    f"against circles, holes and half-planes; the {obj.type} '{obj.name}' touches "
                    "a circle in simulations (event_driven, moreau)",
                )
            rows.append(_circle_row(geometry, k, site, obj, frame))
            continue
        vertices, along = geometry.jaw_vertices(site)
        if obj.type == "half_plane":
            rows += [_pointwise_row(geometry, k, obj, frame, v, s) for v, s in zip(vertices, along)]
        elif obj.type == "implicit":
            rows += [_pointwise_row(geometry, k, obj, frame, v, s) for v, s in _edge_samples(site, vertices, along)]
        else:
            for piece in site.pieces:
                if len(piece) == 1:
                    rows.append(_pointwise_row(geometry, k, obj, frame, vertices[piece[0]], along[piece[0]]))
                    continue
                for object_piece in obj.pieces or ((),):
                    axis = ca.SX.sym(f"axis_{pair.name}_{len(axes)}", 2)
                    axes.append(axis)
                    axis_pairs.append(k)
                    rows += _axis_rows(
                        geometry,
                        k,
                        obj,
                        frame,
                        axis,
                        [(vertices[i], along[i]) for i in piece],
                        object_piece,
                        len(axes) - 1,
                    )
                    guesses.append(_axis_guess(geometry, obj, frame, [vertices[i] for i in piece], object_piece))
        _carried(rows, first, site.link)
    return ContactConstraints(
        ca.vertcat(*axes) if axes else ca.SX(0, 1),
        ca.vertcat(*guesses) if guesses else ca.SX(0, 1),
        axis_pairs,
        rows,
        frames,
        [pair.object for pair in topology.pairs],
    )


def _carried(rows: list[ContactRow], first: int, link: str | None) -> None:
    for row in rows[first:]:
        if row.point is not None:
            row.carrier = link


def _pointwise_row(geometry, k, obj, frame, point, along) -> ContactRow:
    probe = ca.SX.sym("point", 2)
    value = geometry.pointwise(obj, frame, probe)
    normal = ca.gradient(value, probe)
    value, normal = ca.substitute([value, normal], [probe], [point])
    return ContactRow(k, value, point, normal, along)


def _circle_row(geometry, k, site, obj, frame) -> ContactRow:
    """A circle site against a circle (from outside), a hole (from inside) or a half-plane:
    the distance between the surfaces, exact, pushing the circle's material point that
    touches (its centre offset by the radius against the normal)."""
    origin, angle = geometry.site_frame(site)
    centre = origin + rot(angle) @ geometry.P.vec(f"{site.pointer}/centre")
    radius = geometry.P[f"{site.pointer}/radius"]
    probe = ca.SX.sym("centre", 2)
    value = geometry.pointwise(obj, frame, probe) - radius  # the centre's distance, less the radius
    normal = ca.gradient(value, probe)
    value, normal = ca.substitute([value, normal], [probe], [centre])
    return ContactRow(k, value, centre - radius * normal, normal, ca.SX(0))


def _axis_rows(geometry, k, obj, frame, axis, vertices, object_piece, index: int) -> list[ContactRow]:
    n = ca.vertcat(ca.cos(axis[0]), ca.sin(axis[0]))
    rows = [ContactRow(k, axis[1] - ca.dot(n, v), v, -n, s, index) for v, s in vertices]
    rows += [ContactRow(k, extent - axis[1], axis=index) for extent in geometry.support(obj, frame, n, object_piece)]
    return rows


def _axis_guess(geometry, obj, frame, vertices, object_piece) -> ca.SX:
    """A line between the jaw piece and the object: normal from the piece's centroid to the
    object's centre, offset halfway between their extents."""
    centroid = sum(vertices, ca.SX.zeros(2)) / len(vertices)
    towards = geometry.centre(obj, frame, object_piece) - centroid
    theta = ca.atan2(towards[1], towards[0])
    n = ca.vertcat(ca.cos(theta), ca.sin(theta))
    site_extent = ca.dot(n, vertices[0])
    for v in vertices[1:]:
        site_extent = ca.fmax(site_extent, ca.dot(n, v))
    extents = geometry.support(obj, frame, n, object_piece)
    object_extent = extents[0]
    for e in extents[1:]:
        object_extent = ca.fmin(object_extent, e)
    return ca.vertcat(theta, (site_extent + object_extent) / 2)


def _edge_samples(site: SiteTopology, vertices: list[ca.SX], along: list[ca.SX]) -> list[tuple[ca.SX, ca.SX]]:
    """Vertices and SAMPLES_PER_EDGE - 1 points inside every edge (the closing one too)."""
    n = len(vertices)
    if n == 1:
        return [(vertices[0], along[0])]
    edges = [(i, i + 1) for i in range(n - 1)] + ([(n - 1, 0)] if site.closed else [])
    out = [(v, s) for v, s in zip(vertices, along)]
    for i, j in edges:
        length_ij = ca.norm_2(vertices[j] - vertices[i])
        for m in range(1, SAMPLES_PER_EDGE):
            t = m / SAMPLES_PER_EDGE
            out.append(((1 - t) * vertices[i] + t * vertices[j], along[i] + t * length_ij))
    return out
