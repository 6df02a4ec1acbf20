"""Contact pairs of the document's `contacts` in a simulation, a circle site on one body
against a circle, hole, half-plane, polygon or ellipse object carried by another: the indentation q (positive
in contact; the gap is -q), the contact normal n_c (pushing the circle's body out of
contact), the tangent t_c (n_c turned +90 deg), and the generalized directions of a unit
normal and tangent force. A force F_N n_c + F_T t_c acts on the circle's body at the contact
point C = O1 - R1 n_c, and its opposite on the other body at C: its lever includes the -R1 n_c
term that seed 004's Eqs. 30 and 38 drop, so friction turns the circle by -R1 F_T."""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

from flexmech.models.contact.circle_contact import (
    against_circle,
    against_half_plane,
    against_hole,
    against_nearest,
    closest_on_ellipse,
    closest_on_polygon,
)
from flexmech.models.contact.laws import FRICTION_LAWS, FrictionLaw, NormalLaw, friction_law, normal_law
from flexmech.models.contact.laws.penalty import hertz_stiffness
from flexmech.models.contact.schema import ContactPair, Contacts, FrictionFields, NormalLawFields
from flexmech.models.errors import MechanismError
from flexmech.models.graph.planar import rot
from flexmech.models.impacts.coordinates import BodyCoordinates

ONE, SPEED = ("1", 1.0), ("m/s", 1.0)  # units of the laws' numbers (seed 004 gives v0, v1 in m/s)
IMPACT_OBJECTS = ("circle", "hole", "half_plane", "polygon", "ellipse")
DEFAULT_V0, DEFAULT_V1 = 1e-4, 1e-2  # m/s: the slip speeds no Coulomb law reads (masked switching functions)


@dataclass
class PairModel:
    name: str
    law: str  # the normal law's name (models.contact.laws)
    friction: str  # the friction law's name
    indentation: ca.SX  # q(q)
    normal_direction: ca.SX  # generalized force of a unit F_N (n)
    tangent_direction: ca.SX  # of a unit F_T (n)
    K: ca.SX
    exponent: ca.SX
    restitution: ca.SX
    sliding: ca.SX
    adherence: ca.SX
    v0: ca.SX
    v1: ca.SX
    esdu: tuple | None  # (sigma1 + sigma2, L, clearance) for lna_esdu
    length_scale: float  # SI: the clearance, or the pin radius
    normal_law: NormalLaw = None
    friction_law: FrictionLaw = None
    damping: ca.SX = field(default_factory=lambda: ca.SX(0))  # the linear law's dashpot c
    normal_drift: ca.SX = field(default_factory=lambda: ca.SX(0))  # n_c.(v_1 - v_2) at C from driven bodies
    tangent_drift: ca.SX = field(default_factory=lambda: ca.SX(0))  # t_c.(v_1 - v_2) likewise
    point: ca.SX | None = None  # the contact point C
    bodies: tuple = ()  # (the circle's body, the other)
    normal: ca.SX | None = None  # n_c


def pair_model(rb: BodyCoordinates, name: str, pair: ContactPair) -> PairModel:
    """The pair `name` of the document's `contacts`: a circle site on a body against a circle,
    hole or half-plane object carried by another body, or fixed in global axes."""
    book = rb.book
    base = f"/contacts/pairs/{name}"
    site, obj = _surfaces(book.document.contacts, base, pair)
    body1 = rb.body(site.body, f"/contacts/sites/{pair.site}/body")
    body2 = rb.body(obj.body, f"/contacts/objects/{pair.object}/body")
    if body1 is body2:
        raise MechanismError(base, f"the site and the object are both on body '{body1.name}'")
    R1, O1, indentation, n_c, scale, R2_si, clearance = _geometry(rb, name, pair, site, obj, body1, body2)
    t_c = ca.vertcat(-n_c[1], n_c[0])
    C = O1 - R1 * n_c

    def direction(unit):
        return rb.wrench(body1, C, unit) - rb.wrench(body2, C, unit)

    law = pair.normal
    normal = normal_law(law.law, f"{base}/normal/law")
    R1_si = book.value(f"/contacts/sites/{pair.site}/radius")
    K, esdu = _stiffness(rb, base, law, normal, R1_si, R2_si, clearance, obj.type)
    c_r = book.add(f"{base}/normal/restitution", law.restitution, unit=ONE)
    if not 0 < law.restitution <= 1:
        raise MechanismError(
            f"{base}/normal/restitution",
            f"the coefficient of restitution c_r must be in (0, 1], got {law.restitution:g}",
        )
    exponent = book.add(f"{base}/normal/exponent", law.exponent, "positive", ONE)
    friction, sliding, adherence, v0, v1 = _friction(book, base, pair)
    return PairModel(
        name,
        law.law,
        friction.name,
        indentation,
        direction(n_c),
        direction(t_c),
        K,
        exponent,
        c_r,
        sliding,
        adherence,
        v0,
        v1,
        esdu,
        scale,
        normal,
        friction,
        _damping(rb, base, law, normal),
        point=C,
        bodies=(body1, body2),
        normal=n_c,
    )


def _surfaces(contacts: Contacts, base: str, pair: ContactPair):
    """(the site, the object) of a pair, checked for an impact simulation."""
    if pair.site not in contacts.sites:
        raise MechanismError(
            f"{base}/site", f"unknown site '{pair.site}' (sites: {', '.join(contacts.sites) or 'none'})"
        )
    if pair.object not in contacts.objects:
        raise MechanismError(
            f"{base}/object", f"unknown object '{pair.object}' (objects: {', '.join(contacts.objects) or 'none'})"
        )
    site, obj = contacts.sites[pair.site], contacts.objects[pair.object]
    if site.type != "circle":
        raise MechanismError(
            f"{base}/site",
            f"in a simulation a pair's site is a circle on a body (a pin, a roller); '{pair.site}' is a {site.type}",
        )
    if obj.type not in IMPACT_OBJECTS:
        raise MechanismError(
            f"{base}/object",
            f"in a simulation a circle touches a circle, a hole, a half_plane, a "
            f"polygon or an ellipse; '{pair.object}' is a {obj.type}",
        )
    return site, obj


def _friction(book, base: str, pair: ContactPair):
    """(the law, f_d, f_a, v0, v1): a number is Coulomb's mu, both coefficients (0: none)."""
    friction = pair.friction
    if not isinstance(friction, FrictionFields):
        mu = book.number(f"{base}/friction", friction, "dimensionless")
        if book.value(f"{base}/friction") < 0:
            raise MechanismError(
                f"{base}/friction",
                f"a friction coefficient must not be negative, got {book.value(f'{base}/friction'):g}",
            )
        law = FRICTION_LAWS["coulomb" if book.value(f"{base}/friction") > 0 else "none"]
        return law, mu, mu, DEFAULT_V0, DEFAULT_V1
    law = friction_law(friction.law, f"{base}/friction/law")
    for key in ("sliding", "adherence"):
        value = getattr(friction, key)
        if value is not None and value < 0:
            raise MechanismError(
                f"{base}/friction/{key}", f"a friction coefficient must not be negative, got {value:g}"
            )
    if law.speed_events and friction.v1 <= friction.v0:
        raise MechanismError(f"{base}/friction/v1", f"v1 ({friction.v1:g}) must exceed v0 ({friction.v0:g})")
    adherence = friction.adherence if friction.adherence is not None else friction.sliding
    return (
        law,
        book.add(f"{base}/friction/sliding", friction.sliding, unit=ONE),
        book.add(f"{base}/friction/adherence", adherence, unit=ONE),
        book.add(f"{base}/friction/v0", friction.v0, "positive", SPEED),
        book.add(f"{base}/friction/v1", friction.v1, "positive", SPEED),
    )


def _geometry(rb: BodyCoordinates, name: str, pair: ContactPair, site, obj, body1, body2):
    """(R1, O1, indentation, n_c, length scale, R2 (SI or None), clearance (SI or None))."""
    book = rb.book
    s1, s2 = f"/contacts/sites/{pair.site}", f"/contacts/objects/{pair.object}"
    R1 = book.number(f"{s1}/radius", site.radius, "length", "positive")
    O1 = rb.point(body1, book.vector(f"{s1}/centre", site.centre, "length"))
    R1_si = book.value(f"{s1}/radius")
    if obj.type == "half_plane":
        normal = book.vector(f"{s2}/normal", obj.normal, "dimensionless")
        if book.value(f"{s2}/normal/0") == 0 and book.value(f"{s2}/normal/1") == 0:
            raise MechanismError(f"{s2}/normal", "the normal must not be zero")
        n_c = rot(rb.turn(body2) - body2.angle) @ normal / ca.norm_2(normal)
        P2 = rb.point(body2, book.vector(f"{s2}/point", obj.point, "length"))
        return R1, O1, *against_half_plane(O1, R1, P2, n_c), R1_si, None, None
    if obj.type in ("polygon", "ellipse"):
        closest = (_polygon_nearest if obj.type == "polygon" else _ellipse_nearest)(rb, body2, s2, obj, O1)
        return R1, O1, *against_nearest(O1, R1, closest), R1_si, None, None
    R2 = book.number(f"{s2}/radius", obj.radius, "length", "positive")
    R2_si = book.value(f"{s2}/radius")
    O2 = rb.point(body2, book.vector(f"{s2}/centre", obj.centre, "length"))
    if obj.type == "hole":
        clearance = R2_si - R1_si
        if clearance <= 0:
            raise MechanismError(
                f"{s2}/radius",
                f"the clearance of pair '{name}' (hole radius {R2_si:g} m minus "
                f"pin radius {R1_si:g} m) must be positive, got {clearance:g} m",
            )
        return R1, O1, *against_hole(O1, R1, O2, R2), clearance, R2_si, clearance
    return R1, O1, *against_circle(O1, R1, O2, R2), min(R1_si, R2_si), R2_si, None


def _polygon_nearest(rb: BodyCoordinates, body, pointer: str, obj, O1: ca.SX) -> ca.SX:
    book = rb.book
    position = book.vector(f"{pointer}/position", obj.position, "length")
    turn = rot(book.number(f"{pointer}/angle", obj.angle, "angle"))
    corners = [
        rb.point(body, position + turn @ book.vector(f"{pointer}/vertices/{k}", vertex, "length"))
        for k, vertex in enumerate(obj.vertices)
    ]
    return closest_on_polygon(corners, O1)


def _ellipse_nearest(rb: BodyCoordinates, body, pointer: str, obj, O1: ca.SX) -> ca.SX:
    book = rb.book
    axes = book.vector(f"{pointer}/semi_axes", obj.semi_axes, "length")
    for k in (0, 1):
        if book.value(f"{pointer}/semi_axes/{k}") <= 0:
            raise MechanismError(f"{pointer}/semi_axes/{k}", "a semi-axis must be positive")
    centre = rb.point(body, book.vector(f"{pointer}/centre", obj.centre, "length"))
    turn = rot(rb.turn(body) + book.number(f"{pointer}/angle", obj.angle, "angle"))  # in the body's axes
    return closest_on_ellipse(centre, turn, axes[0], axes[1], O1)


def _damping(rb: BodyCoordinates, base: str, law: NormalLawFields, normal: NormalLaw) -> ca.SX:
    """The linear law's dashpot c (document force s / length), SI."""
    if "damping" not in normal.needs:
        return ca.SX(0)
    pointer = f"{base}/normal/damping"
    if law.damping is None:
        raise MechanismError(pointer, f"the {normal.name} law needs the dashpot's `damping` c (force s / length)")
    units = rb.book.document.units
    per = rb.book.si(1.0, "force", pointer) / rb.book.si(1.0, "length", pointer)
    value = rb.book.si(law.damping, "dimensionless", pointer) * per
    return rb.book.add(pointer, value, "nonnegative", (f"{units.force}*s/{units.length}", per))


def _materials(rb: BodyCoordinates, pointer: str, names) -> list[tuple[float, float]]:
    doc, out = rb.book.document, []
    for k, name in enumerate(names):
        if name not in doc.materials:
            raise MechanismError(f"{pointer}/{k}", f"unknown material '{name}' (materials: {', '.join(doc.materials)})")
        material = doc.materials[name]
        if material.nu is None:
            raise MechanismError(
                f"/materials/{name}/nu", f"material '{name}' needs Poisson's ratio nu for the contact stiffness"
            )
        out.append((rb.book.si(material.E, "stress", f"/materials/{name}/E"), float(material.nu)))
    return out


def _stiffness(
    rb: BodyCoordinates,
    base: str,
    law: NormalLawFields,
    normal: NormalLaw,
    R1: float,
    R2: float | None,
    clearance: float | None,
    kind: str,
):
    """(K symbol, ESDU numbers or None). A computed stiffness is a value of the book too; a
    law that needs none has K = 0."""
    book = rb.book
    pointer = f"{base}/normal/stiffness"
    esdu = None
    if normal.name == "lna_esdu":
        if kind != "hole":
            raise MechanismError(f"{base}/normal/law", "the ESDU law (Eq. 18) is for a pin in a hole")
        if law.length is None or law.materials is None:
            raise MechanismError(
                f"{base}/normal/length", "the lna_esdu law needs the contact `length` and the two `materials`"
            )
        (E1, nu1), (E2, nu2) = _materials(rb, f"{base}/normal/materials", law.materials)
        sigma = book.add(
            f"{base}/normal/compliance_sum", (1 - nu1**2) / E1 + (1 - nu2**2) / E2, "positive", ("1/Pa", 1.0)
        )
        esdu = (
            sigma,
            book.number(f"{base}/normal/length", law.length, "length", "positive"),
            book.add(f"{base}/clearance", clearance, "positive", ("m", 1.0)),
        )
    if law.stiffness is None:
        if "stiffness" in normal.needs:
            raise MechanismError(
                pointer,
                f"the {normal.name} law needs the stiffness K (a number in the document's "
                "force / length^exponent, or computed from the materials)",
            )
        return ca.SX(0), esdu
    if isinstance(law.stiffness, str):
        raise MechanismError(pointer, "give K as a number, in the document's force / length^exponent")
    if isinstance(law.stiffness, (int, float)):
        exponent = law.exponent if "exponent" in normal.needs else 1.0
        per = book.si(1.0, "force", pointer) / book.si(1.0, "length", pointer) ** exponent
        units = book.document.units
        return book.add(
            pointer, float(law.stiffness) * per, "positive", (f"{units.force}/{units.length}^{exponent:g}", per)
        ), esdu
    spec = law.stiffness
    (E1, nu1), (E2, nu2) = _materials(rb, f"{pointer}/materials", spec.materials)
    length = None
    if spec.contact == "cylinders":
        if spec.length is None:
            raise MechanismError(f"{pointer}/length", "cylinders need the contact length L (Eq. 16)")
        length = book.si(spec.length, "length", f"{pointer}/length")
    K = hertz_stiffness(spec.contact, E1, nu1, E2, nu2, R1, R2, spec.radius, length)
    return book.add(pointer, K, "positive", (f"N/m^{law.exponent:g}", 1.0)), esdu
