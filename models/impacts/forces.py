"""The smooth forces of an impact model: gravity, constant loads, the curved-beam flexures of
seed 000 (closed-form stiffness, Eq. 2) and the elements that enter by their statics energy
(springs, and any family without an impact hook: models.impacts.elastic), as a potential V(q)
plus the generalized force Q_nc(q) that no potential gives (the flexure whose stiffness turns
with the body, seed 004 Eq. 8)."""

from __future__ import annotations

import casadi as ca

from models.elements import FAMILIES
from models.impacts.bodies import RigidBodies
from models.impacts.condensed import condensed_flexure
from models.planar import rot


def flexures(rb: RigidBodies, condensed: tuple[str, ...]) -> list[tuple[str, ca.SX, ca.SX, ca.SX]]:
    """(name, 1/2 psi.K.psi, psi, K) of every flexure: the elements whose family has an
    impact_flexure hook (the curved beams' closed form) and those condensed from their statics
    (`condensed`: elements with unknowns of their own, models.impacts.condensed)."""
    out = []
    for name, element in rb.book.document.elements.items():
        family = FAMILIES.named(element.type)
        if name in condensed:
            out.append((name, *condensed_flexure(rb, name)))
        elif hasattr(family, "impact_flexure"):
            out.append((name, *family.impact_flexure(rb, name, element)))
    return out


def smooth_forces(rb: RigidBodies, turning: bool, elements: ca.SX, flexures: list) -> tuple[ca.SX, ca.SX]:
    """(V, Q_nc): the potential of the conservative forces and the rest; `elements` is the
    energy of the elements that enter by their statics energy (elastic.element_energy),
    `flexures` those of flexures()."""
    doc, book = rb.book.document, rb.book
    V = elements
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
    for name, energy, psi, K in flexures:
        if turning:
            element = doc.elements[name]
            i = rb.body(element.from_, f"/elements/{name}/from")
            j = rb.body(element.to, f"/elements/{name}/to")
            A3 = ca.diagcat(rot(rb.rotation(j) - rb.rotation(i)), ca.SX(1))
            Q_nc -= ca.mtimes(ca.jacobian(psi, rb.q).T, A3 @ K @ A3.T @ psi)
        else:
            V += energy
    return V, Q_nc


def _load_point(rb: RigidBodies, b, load, base: str) -> ca.SX:
    if load.offset is not None:
        return rb.point(b, rb.book.vector(f"{base}/offset", load.offset, "length"))
    if load.at is not None:
        return rb.drawn_point(b, rb.book.vector(f"{base}/at", load.at, "length"))
    return rb.point(b, ca.SX.zeros(2))
