"""Contact pairs with a penalty law in the statics and in link dynamics: a circle site on a
body against a circle, hole, half-plane, polygon or ellipse object (on a body, or fixed)
pushes with the law's elastic part F = K q^n at an indentation q > 0 (Hertz, seed 004 Eq. 13,
and the elastic part of Hunt-Crossley, Lankarani-Nikravesh and Flores),
the gradient of the potential K q^(n+1) / (n+1). So the pair is part of the mechanism's energy:
the equilibrium solve, the energy form and the link dynamics' time steps all see it, and a
damped simulation settles where the equilibrium solve stands. The damped laws' damping and a
regularized friction act in link dynamics on top (models.contact.pair_forces).

K is in the document's force / length^n and q in its length: the graphs take them through the
unit parameters (nondimensional values of one document unit), as a spring's law does. The
pairs of other laws belong to other analyses (the unilateral law to the quasi-static contact
solve, ESDU's and the linear spring-dashpot to event-driven simulations); a link dynamics run
refuses them."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from flexmech.models.contact.circle_contact import (
    against_circle,
    against_half_plane,
    against_hole,
    against_nearest,
    closest_on_ellipse,
    closest_on_polygon,
)
from flexmech.models.contact.constraints import ContactGeometry
from flexmech.models.contact.laws import FRICTION_LAWS, NORMAL_LAWS, check_law
from flexmech.models.contact.laws.penalty import elastic_power
from flexmech.models.contact.schema import FrictionFields
from flexmech.models.contact.topology import ContactTopology, PairTopology
from flexmech.models.errors import MechanismError
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.planar import rot

# normal laws with an elastic part K q^n, a potential: the statics and link dynamics take them;
# the damped ones' damping acts in link dynamics (models.contact.pair_forces). The linear law's
# dashpot jumps to c qdot at the onset, where an implicit step's equations may have no root.
ELASTIC_LAWS = ("hertz", "hunt_crossley", "lankarani_nikravesh", "flores")
DAMPED_LAWS = ELASTIC_LAWS[1:]


@dataclass
class LawNumbers:
    """What a normal law's force reads (models.contact.laws.NormalLaw.force), as parameters."""

    K: ca.SX
    exponent: ca.SX
    restitution: ca.SX | None = None


@dataclass
class ElasticPair:
    name: str
    indentation: ca.SX  # document length units
    force: ca.SX  # document force units
    potential: ca.SX  # nondimensional, as the mechanism's energy
    topology: PairTopology | None = None
    point: ca.SX | None = None  # where the site's circle meets the object (nondimensional, global)
    normal: ca.SX | None = None  # unit, from the object towards the site


def check_link_dynamics(document) -> None:
    """A link dynamics run takes the elastic pairs, with a regularized friction law or none:
    refuse any other law (and a bare friction coefficient, Coulomb's), naming what it takes."""
    if document.contacts is None:
        return
    for name, pair in document.contacts.pairs.items():
        base = f"/contacts/pairs/{name}"
        check_law(NORMAL_LAWS, "normal", pair.normal.law, "link_dynamics", f"{base}/normal/law")
        site = document.contacts.sites.get(pair.site)
        if site is not None and site.type != "circle":
            raise MechanismError(
                f"{base}/site",
                "a newmark or generalized_alpha simulation takes a pair's site as a "
                f"circle on a body (a pin, a roller, a pad); '{pair.site}' is a {site.type}",
            )
        if not isinstance(pair.normal.stiffness, (int, float)):
            raise MechanismError(
                f"{base}/normal/stiffness",
                "a newmark or generalized_alpha simulation takes the "
                f"{pair.normal.law} law's stiffness K as a number (force / length^exponent in the "
                "document's units), not computed from the materials",
            )
        if isinstance(pair.friction, FrictionFields):
            check_law(FRICTION_LAWS, "friction", pair.friction.law, "link_dynamics", f"{base}/friction/law")
        elif pair.friction != 0:
            raise MechanismError(
                f"{base}/friction",
                "a newmark or generalized_alpha simulation takes a "
                'regularized friction law of the slip speed ({"law": "ambrosio", "sliding": '
                'f_d, "v0": ..., "v1": ...}), not Coulomb\'s coefficient: give the law, or 0',
            )


def elastic(topology: ContactTopology | None) -> list[PairTopology]:
    """The pairs with an elastic law, a circle site and K a number (the collector marks them;
    the others are other analyses' business, and a link dynamics run refuses them)."""
    return [] if topology is None else [pair for pair in topology.pairs if pair.potential]


def elastic_pairs(ctx: AssemblyContext, d: list[ca.SX]) -> list[ElasticPair]:
    topology = ctx.structure.contacts
    pairs = elastic(topology)
    if not pairs:
        return []
    geometry = ContactGeometry(ctx, d, {}, topology)
    unit_length, unit_force = ctx.unit("length"), ctx.unit("force")
    out = []
    for pair in pairs:
        site, obj = topology.sites[pair.site], topology.objects[pair.object]
        origin, angle = geometry.site_frame(site)
        centre = origin + rot(angle) @ ctx.P.vec(f"{site.pointer}/centre")
        radius = ctx.P[f"{site.pointer}/radius"]
        gap, normal = _indentation(geometry, obj, centre, radius)
        q = gap / unit_length
        K, n = _numbers(ctx, pair)
        force = elastic_power(K, ca.fmax(q, 0.0), n)
        potential = elastic_power(K, ca.fmax(q, 0.0), n + 1) / (n + 1) * unit_force * unit_length
        out.append(ElasticPair(pair.name, q, force, potential, pair, centre - radius * normal, normal))
    return out


def contact_potential(ctx: AssemblyContext, d: list[ca.SX]) -> ca.SX:
    return sum((pair.potential for pair in elastic_pairs(ctx, d)), ca.SX(0))


def contact_wrenches(ctx: AssemblyContext, d: list[ca.SX]) -> list[ca.SX]:
    """Per body, the wrench [Fx, Fy, M about its reference point] the elastic pairs apply to
    it: minus the potential's gradient in its displacement."""
    if not elastic(ctx.structure.contacts):
        return [ca.SX.zeros(3) for _ in range(ctx.n_bodies)]
    symbols = [ca.SX.sym(f"d{b}", 3) for b in range(ctx.n_bodies)]
    potential = contact_potential(ctx, symbols)
    return [
        ca.substitute(-ca.gradient(potential, symbols[b]), ca.vertcat(*symbols), ca.vertcat(*d))
        for b in range(ctx.n_bodies)
    ]


def contact_outputs(ctx: AssemblyContext, d: list[ca.SX]) -> list[tuple[str, str, ca.SX]]:
    """(name, kind, nondimensional value): each elastic pair's normal force and indentation."""
    out = []
    for pair in elastic_pairs(ctx, d):
        out.append((f"contacts.{pair.name}.normal_force", "force", pair.force * ctx.unit("force")))
        out.append((f"contacts.{pair.name}.indentation", "length", pair.indentation * ctx.unit("length")))
    return out


def _indentation(geometry: ContactGeometry, obj, centre: ca.SX, radius: ca.SX) -> tuple[ca.SX, ca.SX]:
    """(indentation, unit normal from the object towards the circle's centre)."""
    P = geometry.P
    frame = geometry.object_frame(obj)
    base = obj.pointer
    if obj.type == "circle":
        return against_circle(centre, radius, frame.origin, P[f"{base}/radius"])
    if obj.type == "hole":
        return against_hole(centre, radius, frame.origin, P[f"{base}/radius"])
    if obj.type == "half_plane":
        normal = rot(frame.angle) @ P.vec(f"{base}/normal")
        return against_half_plane(centre, radius, frame.origin, normal / ca.norm_2(normal))
    if obj.type == "polygon":
        count = 1 + max(max(piece) for piece in obj.pieces)
        corners = [frame.origin + rot(frame.angle) @ P.vec(f"{base}/vertices/{k}") for k in range(count)]
        return against_nearest(centre, radius, closest_on_polygon(corners, centre))
    if obj.type == "ellipse":
        nearest = closest_on_ellipse(
            frame.origin, rot(frame.angle), P[f"{base}/semi_axes/0"], P[f"{base}/semi_axes/1"], centre
        )
        return against_nearest(centre, radius, nearest)
    raise MechanismError(
        f"{base}/type",
        f"an elastic contact pair takes circles, holes, half-planes, polygons and "
        f"ellipses, not the {obj.type} '{obj.name}'",
    )


def _numbers(ctx: AssemblyContext, pair: PairTopology) -> tuple[ca.SX, ca.SX]:
    numbers = law_numbers(ctx, pair)
    return numbers.K, numbers.exponent


def law_numbers(ctx: AssemblyContext, pair: PairTopology) -> LawNumbers:
    """The pair's law's numbers (document units; models.contact.collect_contacts adds them)."""
    base = f"{pair.pointer}/normal"
    restitution = ctx.P[f"{base}/restitution"] if pair.normal_law in DAMPED_LAWS else None
    return LawNumbers(ctx.P[f"{base}/stiffness"], ctx.P[f"{base}/exponent"], restitution)
