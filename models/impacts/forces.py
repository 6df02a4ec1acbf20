"""The smooth forces of an impact model: gravity, constant loads, linear springs and the
curved-beam flexures of seed 000 (closed-form stiffness, Eq. 2), as a potential V(q) plus the
generalized force Q_nc(q) that no potential gives (the flexure whose stiffness turns with the
body, seed 004 Eq. 8)."""

from __future__ import annotations

import casadi as ca

from models import curved_beam as kernel
from models.errors import MechanismError
from models.impacts.bodies import RigidBodies
from models.planar import rot

SUPPORTED = ("curved_beam", "spring", "pin", "slider")


def smooth_forces(rb: RigidBodies, turning: bool) -> tuple[ca.SX, ca.SX]:
    """(V, Q_nc): the potential of the conservative forces and the rest."""
    doc, book = rb.book.document, rb.book
    V = ca.SX(0)
    Q_nc = ca.SX.zeros(rb.size)
    if doc.gravity is not None:
        V += rb.gravity_energy(book.vector("/gravity", doc.gravity, "acceleration"))
    for name, load in doc.loads.items():
        base = f"/loads/{name}"
        b = rb.body(load.body, f"{base}/body")
        if load.type == "force":
            at = _load_point(rb, b, load, base)
            V -= ca.dot(book.vector(f"{base}/force", load.force, "force"), at)
        elif load.type == "moment":
            V -= book.number(f"{base}/moment", load.moment, "moment") * rb.rotation(b)
        # a displacement drives its body (models.impacts.bodies): no force
    for name, element in doc.elements.items():
        base = f"/elements/{name}"
        if element.type == "curved_beam":
            energy, psi, K = _flexure(rb, name, element, base)
            if turning:
                i, j = rb.body(element.from_, f"{base}/from"), rb.body(element.to, f"{base}/to")
                A3 = ca.diagcat(rot(rb.rotation(j) - rb.rotation(i)), ca.SX(1))
                Q_nc -= ca.mtimes(ca.jacobian(psi, rb.q).T, A3 @ K @ A3.T @ psi)
            else:
                V += energy
        elif element.type == "spring":
            V += _spring(rb, name, element, base)
        elif element.type in ("pin", "slider"):
            continue  # a constraint (models.impacts.joints)
        else:
            raise MechanismError(f"{base}/type", f"a {element.type} element is not part of impact simulations "
                                 f"(they take {', '.join(SUPPORTED)})")
    return V, Q_nc


def flexure_energy(rb: RigidBodies) -> ca.SX:
    """The strain energy 1/2 psi.K.psi of every curved beam (reported with either stiffness)."""
    total = ca.SX(0)
    for name, element in rb.book.document.elements.items():
        if element.type == "curved_beam":
            total += _flexure(rb, name, element, f"/elements/{name}")[0]
    return total


def spring_energy(rb: RigidBodies) -> ca.SX:
    total = ca.SX(0)
    for name, element in rb.book.document.elements.items():
        if element.type == "spring":
            total += _spring(rb, name, element, f"/elements/{name}")
    return total


def _load_point(rb: RigidBodies, b, load, base: str) -> ca.SX:
    if load.offset is not None:
        return rb.point(b, rb.book.vector(f"{base}/offset", load.offset, "length"))
    if load.at is not None:
        return rb.drawn_point(b, rb.book.vector(f"{base}/at", load.at, "length"))
    return rb.point(b, ca.SX.zeros(2))


def _flexure(rb: RigidBodies, name: str, el, base: str):
    """(1/2 psi.K.psi, psi, K): psi is seed 000's deformation of the arc's end relative to its
    start (Eqs. 5-8) in the end frame S_fj, exact for any rotation of the start body."""
    book, doc = rb.book, rb.book.document
    if el.material not in doc.materials:
        raise MechanismError(f"{base}/material", f"unknown material '{el.material}'")
    if el.section not in doc.sections or not hasattr(doc.sections[el.section], "b"):
        raise MechanismError(f"{base}/section", f"'{el.section}' is not a rectangle section of the document")
    section = doc.sections[el.section]
    E = book.number(f"/materials/{el.material}/E", doc.materials[el.material].E, "stress", "positive")
    width = book.number(f"/sections/{el.section}/b", section.b, "length", "positive")
    h = book.number(f"/sections/{el.section}/h", section.h, "length", "positive")
    r = book.number(f"{base}/radius", el.radius, "length", "positive")
    theta_f = book.number(f"{base}/arc_angle", el.arc_angle, "angle", "positive")
    start_angle = book.number(f"{base}/start_angle", el.start_angle, "angle")
    centre = book.vector(f"{base}/center", el.center, "length")
    i, j = rb.body(el.from_, f"{base}/from"), rb.body(el.to, f"{base}/to")
    if el.direction == "cw":  # the model runs counter-clockwise: swap the ends
        i, j, start_angle = j, i, start_angle - theta_f
    arc = kernel.arc_geometry(centre, r, start_angle, theta_f)
    hoist = book.hoist
    start = rb.point(i, hoist(rb.body_offset(i, arc.start_point)))
    end = rb.point(j, hoist(rb.body_offset(j, arc.end_point)))
    chord, frame = hoist(arc.end_point - arc.start_point), hoist(rot(arc.end_frame_angle))
    relative = rot(-rb.rotation(i)) @ (end - start) - chord
    psi = ca.vertcat(frame.T @ relative, rb.rotation(j) - rb.rotation(i))
    K = hoist(kernel.stiffness(r, theta_f, E * width * h**3 / 12))
    return 0.5 * ca.dot(psi, K @ psi), psi, K


def _spring(rb: RigidBodies, name: str, el, base: str) -> ca.SX:
    if el.stiffness is None:
        raise MechanismError(f"{base}/law", "impact simulations take linear springs (`stiffness`)")
    book = rb.book
    i, j = rb.body(el.from_, f"{base}/from"), rb.body(el.to, f"{base}/to")
    if el.kind == "torsional":
        k = book.number(f"{base}/stiffness", el.stiffness, "rotational_stiffness", "nonnegative")
        rest = book.number(f"{base}/rest", el.rest if el.rest is not None else 0.0, "angle")
        return 0.5 * k * (rb.rotation(j) - rb.rotation(i) - rest) ** 2
    k = book.number(f"{base}/stiffness", el.stiffness, "stiffness", "nonnegative")
    a_drawn = book.vector(f"{base}/from_at", el.from_at, "length") if el.from_at is not None else i.position
    b_drawn = book.vector(f"{base}/to_at", el.to_at, "length") if el.to_at is not None else j.position
    a, b = rb.drawn_point(i, a_drawn), rb.drawn_point(j, b_drawn)
    drawn = ca.norm_2(b_drawn - a_drawn)
    rest = book.number(f"{base}/rest", el.rest, "length", "nonnegative") if el.rest is not None else drawn
    return 0.5 * k * (ca.sqrt(ca.sumsqr(b - a) + 1e-300) - rest) ** 2
