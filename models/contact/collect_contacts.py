"""Read a document's `contacts` into parameters (through the collector) and a topology,
checking every reference and shape: unknown sites, objects, bodies and links; radii and
semi-axes that are not positive; self-intersecting polygons; negative friction; a surface
of a link whose thickness is unknown; unsafe implicit expressions."""

from __future__ import annotations

import numpy as np

from flexmech.models.contact.elastic_pairs import DAMPED_LAWS, ELASTIC_LAWS
from flexmech.models.contact.laws import friction_law, normal_law
from flexmech.models.contact.pair_forces import REGULARIZED
from flexmech.models.contact.polygons import convex_pieces, self_intersection, signed_area
from flexmech.models.contact.schema import Contacts, FrictionFields, JawSite
from flexmech.models.contact.topology import ContactTopology, ObjectTopology, PairTopology, SiteTopology
from flexmech.models.documents.expression import compile_expression, finite_on
from flexmech.models.elements import FAMILIES
from flexmech.models.errors import MechanismError
from flexmech.models.graph.structure import ElementTopology

IMPLICIT_PROBES = ((0.0, 0.0), (1.0, 0.5), (-0.7, 1.3))  # where g must be a finite number (object frame)


CIRCLE_TOUCHES = ("circle", "hole", "half_plane", "polygon", "ellipse")  # polygons, ellipses: simulations only


def collect_contacts(c, contacts: Contacts | None, elements: list[ElementTopology]) -> ContactTopology | None:
    if contacts is None:
        return None
    objects = tuple(_collect_object(c, name, obj) for name, obj in contacts.objects.items())
    links = {t.name: t for t in elements if getattr(FAMILIES.of(t), "centre_line_sites", False)}
    sites = tuple(_collect_site(c, name, site, links) for name, site in contacts.sites.items())
    pairs = [_collect_pair(c, name, pair, sites, objects) for name, pair in contacts.pairs.items()]
    return ContactTopology(objects, sites, tuple(pairs))


def _collect_pair(
    c, name: str, pair, sites: tuple[SiteTopology, ...], objects: tuple[ObjectTopology, ...]
) -> PairTopology:
    """One pair's parameters (its friction coefficient, an elastic law's numbers) and topology."""
    base = f"/contacts/pairs/{name}"
    site_index, object_index = _pair_indices(base, pair, sites, objects)
    site = sites[site_index]
    normal_law(pair.normal.law, f"{base}/normal/law")
    potential = (
        pair.normal.law in ELASTIC_LAWS and site.type == "circle" and isinstance(pair.normal.stiffness, (int, float))
    )
    if potential:
        _collect_elastic(c, base, pair)
        if isinstance(pair.friction, FrictionFields) and pair.friction.law in REGULARIZED:
            if pair.friction.v1 <= pair.friction.v0:
                raise MechanismError(
                    f"{base}/friction/v1",
                    f"must exceed v0 ({pair.friction.v0:g} m/s): the law ramps the friction up between them",
                )
            for speed in ("v0", "v1"):  # m/s (models.contact.pair_forces)
                c.add(f"{base}/friction/{speed}", getattr(pair.friction, speed), "dimensionless", "positive")
    if isinstance(pair.friction, FrictionFields):
        friction_law(pair.friction.law, f"{base}/friction/law")
    friction = pair.friction_pointer(base)
    c.add(friction, pair.friction_coefficient(), "dimensionless", "nonnegative")
    law = pair.friction.law if isinstance(pair.friction, FrictionFields) else "coulomb"
    return PairTopology(name, site_index, object_index, friction, pair.normal.law, law, potential)


def _pair_indices(base: str, pair, sites, objects) -> tuple[int, int]:
    """The indices of the pair's site and object, which must exist and be able to touch."""
    object_names, site_names = [o.name for o in objects], [s.name for s in sites]
    if pair.site not in site_names:
        raise MechanismError(f"{base}/site", f"unknown site '{pair.site}' (sites: {', '.join(site_names) or 'none'})")
    if pair.object not in object_names:
        raise MechanismError(
            f"{base}/object", f"unknown object '{pair.object}' (objects: {', '.join(object_names) or 'none'})"
        )
    site, obj = sites[site_names.index(pair.site)], objects[object_names.index(pair.object)]
    if site.type == "circle" and obj.type not in CIRCLE_TOUCHES:
        raise MechanismError(
            f"{base}/object",
            f"a circle site touches circles, holes, half-planes, polygons and "
            f"ellipses, not the {obj.type} '{obj.name}'",
        )
    if site.type == "surface" and obj.type == "polygon":
        raise MechanismError(
            f"{base}/object",
            f"a link surface cannot touch the polygon '{obj.name}': polygons "
            "touch jaws (give the link a jaw, or describe the object as an implicit curve)",
        )
    return site_names.index(pair.site), object_names.index(pair.object)


def _collect_elastic(c, base: str, pair) -> None:
    """An elastic pair's numbers (models.contact.elastic_pairs): K in the document's force /
    length^n and n, read through the unit parameters; a damped law's restitution and the
    approach speed at its contact's onset (set by the run that locates it:
    service.dynamics.onsets). (A stiffness computed from materials is the impact model's, which
    computes it; a link dynamics run asks for a number.)"""
    c.add(f"{base}/normal/exponent", pair.normal.exponent, "dimensionless", "positive")
    c.add(f"{base}/normal/stiffness", pair.normal.stiffness, "dimensionless", "positive")
    if pair.normal.law in DAMPED_LAWS:
        if not 0 < pair.normal.restitution <= 1:
            raise MechanismError(f"{base}/normal/restitution", f"must be in (0, 1], got {pair.normal.restitution:g}")
        c.add(f"{base}/normal/restitution", pair.normal.restitution, "dimensionless", "positive")
        c.add(f"{base}/normal/onset_speed", 1.0, "dimensionless", "positive")  # no contact yet: any will do
    for kind in ("length", "force"):
        c.unit_parameter(kind)


def _vertices(c, base: str, vertices) -> np.ndarray:
    """Add each vertex (length) and return them in SI, for shape checks."""
    out = []
    for k, vertex in enumerate(vertices):
        c.add_vec(f"{base}/{k}", vertex, "length")
        out.append(c.values[-2:])
    return np.array(out, dtype=float)


def _body(c, pointer: str, name: str | None) -> int | None:
    return None if name is None else c.body_index(name, pointer)


def _collect_object(c, name: str, obj) -> ObjectTopology:
    base = f"/contacts/objects/{name}"
    body = _body(c, f"{base}/body", obj.body)
    if obj.type in ("circle", "hole"):
        c.add_vec(f"{base}/centre", obj.centre, "length")
        c.add(f"{base}/radius", obj.radius, "length", "positive")
        return ObjectTopology(name, obj.type, body)
    if obj.type == "ellipse":
        c.add_vec(f"{base}/centre", obj.centre, "length")
        for k, value in enumerate(obj.semi_axes):
            c.add(f"{base}/semi_axes/{k}", value, "length", "positive")
        c.add(f"{base}/angle", obj.angle, "angle")
        return ObjectTopology(name, "ellipse", body)
    if obj.type == "half_plane":
        c.add_vec(f"{base}/point", obj.point, "length")
        c.add_vec(f"{base}/normal", obj.normal, "dimensionless")
        if not np.any(c.values[-2:]):
            raise MechanismError(f"{base}/normal", "the normal must not be zero")
        return ObjectTopology(name, "half_plane", body)
    c.add_vec(f"{base}/position", obj.position, "length")
    c.add(f"{base}/angle", obj.angle, "angle")
    if obj.type == "polygon":
        return ObjectTopology(
            name, "polygon", body, _polygon_pieces(_vertices(c, f"{base}/vertices", obj.vertices), f"{base}/vertices")
        )
    pointer = f"{base}/expression"
    build = compile_expression(obj.expression, pointer, variable="x", names=("y",))
    for x, y in IMPLICIT_PROBES:
        finite_on(build, pointer, (x,), what="x", env={"y": y})
    c.unit_parameter("length")  # the expression is in document length units
    return ObjectTopology(name, "implicit", body, expression=obj.expression)


def _polygon_pieces(vertices: np.ndarray, pointer: str) -> tuple[tuple[int, ...], ...]:
    crossing = self_intersection(vertices)
    if crossing is not None:
        i, j = crossing
        n = len(vertices)
        raise MechanismError(
            pointer, f"the polygon intersects itself: edge {i}-{(i + 1) % n} meets edge {j}-{(j + 1) % n}"
        )
    if abs(signed_area(vertices)) <= 1e-12 * max(1e-300, float(np.ptp(vertices, axis=0).max()) ** 2):
        raise MechanismError(pointer, "the polygon has no area")
    return convex_pieces(vertices)


def _collect_site(c, name: str, site, links: dict[str, ElementTopology]) -> SiteTopology:
    base = f"/contacts/sites/{name}"
    if site.type == "surface":
        link = _link(site.link, f"{base}/link", links)
        if site.side != "centre_line" and not _has_thickness(c, link):
            raise MechanismError(
                f"{base}/side",
                f"link '{site.link}' has no thickness (section "
                f"'{link.section.name}' gives no c): a surface needs one; use side 'centre_line' "
                "or give the section c",
            )
        return SiteTopology(name, "surface", link=site.link, side=site.side)
    if site.type == "circle":
        body = _body(c, f"{base}/body", site.body)
        c.add_vec(f"{base}/centre", site.centre, "length")
        c.add(f"{base}/radius", site.radius, "length", "positive")
        return SiteTopology(name, "circle", body=body)
    return _collect_jaw(c, base, name, site, links)


def _collect_jaw(c, base: str, name: str, site: JawSite, links) -> SiteTopology:
    if (site.body is None) == (site.link is None):
        raise MechanismError(base, "a jaw is carried by a body or by a link's end: give one of body and link")
    body = _body(c, f"{base}/body", site.body)
    if site.link is not None:
        _link(site.link, f"{base}/link", links)
    vertices = _vertices(c, f"{base}/vertices", site.vertices)
    closed = len(vertices) >= 3 if site.closed is None else site.closed
    if closed:
        if len(vertices) < 3:
            raise MechanismError(f"{base}/vertices", f"a closed jaw needs at least 3 vertices, got {len(vertices)}")
        pieces = _polygon_pieces(vertices, f"{base}/vertices")
    else:
        lengths = np.linalg.norm(np.diff(vertices, axis=0), axis=1)
        if np.any(lengths == 0):
            k = int(np.argmin(lengths))
            raise MechanismError(f"{base}/vertices/{k + 1}", f"vertex {k + 1} repeats vertex {k}")
        pieces = tuple((k, k + 1) for k in range(len(vertices) - 1)) or ((0,),)
    return SiteTopology(
        name, "jaw", body=body, link=site.link, end=site.end, n_vertices=len(vertices), closed=closed, pieces=pieces
    )


def _link(name: str, pointer: str, links: dict[str, ElementTopology]) -> ElementTopology:
    if name not in links:
        raise MechanismError(pointer, f"unknown link '{name}' (links: {', '.join(links) or 'none'})")
    return links[name]


def _has_thickness(c, link) -> bool:
    section = c.doc.sections[link.section.name]
    return getattr(section, "shape", "rectangle") != "general" or section.c is not None
