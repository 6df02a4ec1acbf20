"""Contact pairs between body surfaces: the indentation q (positive in contact; the gap is
-q), the contact normal n_c (pushing the circle's body out of contact), the tangent t_c (n_c
turned +90 deg), and the generalized directions of a unit normal and tangent force. A force
F_N n_c + F_T t_c acts on the circle's body at the contact point C = O1 - R1 n_c, and its
opposite on the other body at C: its lever includes the -R1 n_c term that seed 004's Eqs. 30
and 38 drop, so friction turns the circle by -R1 F_T."""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

from models.errors import MechanismError
from models.impacts.bodies import RigidBodies
from models.impacts.document import ImpactPair
from models.impacts.laws import hertz_stiffness
from models.planar import rot

ONE, SPEED = ("1", 1.0), ("m/s", 1.0)  # units of the laws' numbers (seed 004 gives v0, v1 in m/s)


@dataclass
class PairModel:
    name: str
    law: str
    friction: str  # ambrosio | coulomb | none
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
    normal_drift: ca.SX = field(default_factory=lambda: ca.SX(0))  # n_c.(v_1 - v_2) at C from driven bodies
    tangent_drift: ca.SX = field(default_factory=lambda: ca.SX(0))  # t_c.(v_1 - v_2) likewise
    point: ca.SX | None = None  # the contact point C
    bodies: tuple = ()  # (the circle's body, the other)
    normal: ca.SX | None = None  # n_c


def pair_model(rb: RigidBodies, name: str, pair: ImpactPair) -> PairModel:
    book, doc = rb.book, rb.book.document
    base = f"/impacts/pairs/{name}"
    surfaces = doc.impacts.surfaces
    for k, surface in enumerate(pair.surfaces):
        if surface not in surfaces:
            raise MechanismError(f"{base}/surfaces/{k}", f"unknown surface '{surface}' (surfaces: "
                                 f"{', '.join(surfaces) or 'none'})")
    first, second = (surfaces[s] for s in pair.surfaces)
    if first.type != "circle":
        raise MechanismError(f"{base}/surfaces/0", f"the first surface of a pair is a circle, '{pair.surfaces[0]}' is a "
                             f"{first.type}")
    body1, body2 = rb.body(first.body, f"/impacts/surfaces/{pair.surfaces[0]}/body"), \
        rb.body(second.body, f"/impacts/surfaces/{pair.surfaces[1]}/body")
    if body1.name == body2.name:
        raise MechanismError(f"{base}/surfaces", "both surfaces are on the same body")
    R1, O1, indentation, n_c, scale, R2_si, clearance = _geometry(rb, name, pair, first, second, body1, body2)
    t_c = ca.vertcat(-n_c[1], n_c[0])
    C = O1 - R1 * n_c

    def direction(unit):
        return rb.wrench(body1, C, unit) - rb.wrench(body2, C, unit)

    law = pair.normal
    R1_si = book.value(f"/impacts/surfaces/{pair.surfaces[0]}/radius")
    K, esdu = _stiffness(rb, base, law, R1_si, R2_si, clearance, second.type)
    c_r = book.add(f"{base}/normal/restitution", law.restitution, unit=ONE)
    if not 0 < law.restitution <= 1:
        raise MechanismError(f"{base}/normal/restitution", f"the coefficient of restitution c_r must be in (0, 1], "
                             f"got {law.restitution:g}")
    friction = pair.friction
    _check_friction(base, friction)
    adherence = friction.adherence if friction.adherence is not None else friction.sliding
    return PairModel(
        name, law.law, friction.law, indentation, direction(n_c), direction(t_c), K,
        book.add(f"{base}/normal/exponent", law.exponent, "positive", ONE), c_r,
        book.add(f"{base}/friction/sliding", friction.sliding, unit=ONE),
        book.add(f"{base}/friction/adherence", adherence, unit=ONE),
        book.add(f"{base}/friction/v0", friction.v0, "positive", SPEED),
        book.add(f"{base}/friction/v1", friction.v1, "positive", SPEED),
        esdu, scale, point=C, bodies=(body1, body2), normal=n_c)


def _check_friction(base: str, friction) -> None:
    for name in ("sliding", "adherence"):
        value = getattr(friction, name)
        if value is not None and value < 0:
            raise MechanismError(f"{base}/friction/{name}", f"a friction coefficient must not be negative, got {value:g}")
    if friction.law == "ambrosio" and friction.v1 <= friction.v0:
        raise MechanismError(f"{base}/friction/v1", f"v1 ({friction.v1:g}) must exceed v0 ({friction.v0:g})")


def _geometry(rb: RigidBodies, name: str, pair: ImpactPair, first, second, body1, body2):
    """(R1, O1, indentation, n_c, length scale, R2 (SI or None), clearance (SI or None))."""
    book = rb.book
    s1, s2 = (f"/impacts/surfaces/{s}" for s in pair.surfaces)
    R1 = book.number(f"{s1}/radius", first.radius, "length", "positive")
    O1 = rb.point(body1, book.vector(f"{s1}/centre", first.centre, "length"))
    R1_si = book.value(f"{s1}/radius")
    if second.type == "line":
        normal = book.vector(f"{s2}/normal", second.normal, "dimensionless")
        if book.value(f"{s2}/normal/0") == 0 and book.value(f"{s2}/normal/1") == 0:
            raise MechanismError(f"{s2}/normal", "the normal must not be zero")
        n_c = rot(rb.turn(body2) - body2.angle) @ normal / ca.norm_2(normal)
        P2 = rb.point(body2, book.vector(f"{s2}/point", second.point, "length"))
        return R1, O1, R1 - ca.dot(O1 - P2, n_c), n_c, R1_si, None, None
    R2 = book.number(f"{s2}/radius", second.radius, "length", "positive")
    R2_si = book.value(f"{s2}/radius")
    O2 = rb.point(body2, book.vector(f"{s2}/centre", second.centre, "length"))
    e = O1 - O2
    distance = ca.sqrt(ca.dot(e, e) + 1e-300)
    if second.type == "hole":
        clearance = R2_si - R1_si
        if clearance <= 0:
            raise MechanismError(f"{s2}/radius", f"the clearance of pair '{name}' (hole radius {R2_si:g} m minus "
                                 f"pin radius {R1_si:g} m) must be positive, got {clearance:g} m")
        return R1, O1, distance - (R2 - R1), -e / distance, clearance, R2_si, clearance
    return R1, O1, R1 + R2 - distance, e / distance, min(R1_si, R2_si), R2_si, None


def _materials(rb: RigidBodies, pointer: str, names) -> list[tuple[float, float]]:
    doc, out = rb.book.document, []
    for k, name in enumerate(names):
        if name not in doc.materials:
            raise MechanismError(f"{pointer}/{k}", f"unknown material '{name}' (materials: {', '.join(doc.materials)})")
        material = doc.materials[name]
        if material.nu is None:
            raise MechanismError(f"/materials/{name}/nu", f"material '{name}' needs Poisson's ratio nu for the "
                                 "contact stiffness")
        out.append((rb.book.si(material.E, "stress", f"/materials/{name}/E"), float(material.nu)))
    return out


def _stiffness(rb: RigidBodies, base: str, law, R1: float, R2: float | None, clearance: float | None, kind: str):
    """(K symbol, ESDU numbers or None). A computed stiffness is a value of the book too."""
    book = rb.book
    pointer = f"{base}/normal/stiffness"
    esdu = None
    if law.law == "lna_esdu":
        if kind != "hole":
            raise MechanismError(f"{base}/normal/law", "the ESDU law (Eq. 18) is for a pin in a hole")
        if law.length is None or law.materials is None:
            raise MechanismError(f"{base}/normal/length", "the lna_esdu law needs the contact `length` and the two "
                                 "`materials`")
        (E1, nu1), (E2, nu2) = _materials(rb, f"{base}/normal/materials", law.materials)
        sigma = book.add(f"{base}/normal/compliance_sum", (1 - nu1**2) / E1 + (1 - nu2**2) / E2, "positive",
                         ("1/Pa", 1.0))
        esdu = (sigma, book.number(f"{base}/normal/length", law.length, "length", "positive"),
                book.add(f"{base}/clearance", clearance, "positive", ("m", 1.0)))
    if isinstance(law.stiffness, str):
        raise MechanismError(pointer, "give K as a number, in the document's force / length^exponent")
    if isinstance(law.stiffness, (int, float)):
        per = book.si(1.0, "force", pointer) / book.si(1.0, "length", pointer) ** law.exponent
        units = book.document.units
        return book.add(pointer, float(law.stiffness) * per, "positive",
                        (f"{units.force}/{units.length}^{law.exponent:g}", per)), esdu
    spec = law.stiffness
    (E1, nu1), (E2, nu2) = _materials(rb, f"{pointer}/materials", spec.materials)
    length = None
    if spec.contact == "cylinders":
        if spec.length is None:
            raise MechanismError(f"{pointer}/length", "cylinders need the contact length L (Eq. 16)")
        length = book.si(spec.length, "length", f"{pointer}/length")
    K = hertz_stiffness(spec.contact, E1, nu1, E2, nu2, R1, R2, spec.radius, length)
    return book.add(pointer, K, "positive", (f"N/m^{law.exponent:g}", 1.0)), esdu
