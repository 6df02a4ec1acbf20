"""The rigid bodies of an impact model: coordinates q = (x, y, theta) per free body, the
displacement of its mass centre from the drawn pose and its rotation, so the mass matrix is
diagonal and constant; points carried by bodies; the kinetic and gravity energies."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from models.errors import MechanismError
from models.impacts.book import ParameterBook
from models.planar import rot


@dataclass
class RigidBody:
    name: str
    first: int | None  # index of x in q; None for a fixed body
    position: ca.SX  # drawn reference point
    angle: ca.SX
    centre_offset: ca.SX  # mass centre from the reference point, body axes
    mass: ca.SX | None = None
    inertia: ca.SX | None = None  # about the mass centre
    drive: ca.SX | None = None  # a driven body's displacement [dx, dy, rotation] (a prescribed motion)


class RigidBodies:
    def __init__(self, book: ParameterBook):
        self.book = book
        self.bodies: dict[str, RigidBody] = {}
        doc = book.document
        driven = _drives(book)
        n = 0
        for name, body in doc.bodies.items():
            base = f"/bodies/{name}"
            position = book.vector(f"{base}/position", body.position, "length")
            angle = book.number(f"{base}/angle", body.angle, "angle")
            offset = (book.vector(f"{base}/center_of_mass", body.center_of_mass, "length")
                      if body.center_of_mass is not None else ca.SX.zeros(2))
            moving = name not in driven and not body.fixed
            rigid = RigidBody(name, n if moving else None, position, angle, offset, drive=driven.get(name))
            if moving:
                if body.mass is None:
                    raise MechanismError(f"{base}/mass", f"body '{name}' moves and has no mass: an impact simulation "
                                         "needs every free body's mass and inertia")
                if body.inertia is None:
                    raise MechanismError(f"{base}/inertia", f"body '{name}' moves and has no inertia: give its "
                                         "moment of inertia about its reference point")
                rigid.mass = book.number(f"{base}/mass", body.mass, "mass", "positive")
                about_reference = book.number(f"{base}/inertia", body.inertia, "inertia", "positive")
                rigid.inertia = about_reference - rigid.mass * ca.dot(offset, offset)
                n += 3
            self.bodies[name] = rigid
        if n == 0:
            raise MechanismError("/bodies", "every body is fixed: nothing moves")
        self.size = n
        self.q = ca.SX.sym("q", n)
        self.v = ca.SX.sym("v", n)

    def body(self, name: str | None, pointer: str) -> RigidBody:
        """The body `name`; None is the world, fixed at the origin (an object given without
        a body is in global axes and never moves)."""
        if name is None:
            return RigidBody("world", None, ca.SX.zeros(2), ca.SX(0), ca.SX.zeros(2))
        if name not in self.bodies:
            raise MechanismError(pointer, f"unknown body '{name}' (bodies: {', '.join(self.bodies)})")
        return self.bodies[name]

    def centre(self, b: RigidBody) -> ca.SX:
        """Mass centre, global (a driven body turns about its reference point)."""
        if b.drive is not None:
            return b.position + b.drive[:2] + rot(b.angle + b.drive[2]) @ b.centre_offset
        drawn = b.position + rot(b.angle) @ b.centre_offset
        return drawn if b.first is None else drawn + self.q[b.first:b.first + 2]

    def turn(self, b: RigidBody) -> ca.SX:
        return b.angle + self.rotation(b)

    def rotation(self, b: RigidBody) -> ca.SX:
        if b.drive is not None:
            return b.drive[2]
        return ca.SX(0) if b.first is None else self.q[b.first + 2]

    def point(self, b: RigidBody, offset: ca.SX) -> ca.SX:
        """A point given in the body's axes from its reference point, global."""
        if b.first is None and b.drive is None:
            return self.book.hoist(b.position + rot(b.angle) @ offset)
        return self.centre(b) + rot(self.turn(b)) @ (offset - b.centre_offset)

    def body_offset(self, b: RigidBody, at: ca.SX) -> ca.SX:
        """The body-axes offset of a point given globally in the drawn pose."""
        return rot(b.angle).T @ (at - b.position)

    def drawn_point(self, b: RigidBody, at: ca.SX) -> ca.SX:
        """A point given globally in the drawn pose, carried by the body."""
        return self.point(b, self.body_offset(b, at))

    def wrench(self, b: RigidBody, at: ca.SX, force: ca.SX) -> ca.SX:
        """Generalized force (n) of `force` applied at the global point `at` of body b."""
        Q = ca.SX.zeros(self.size)
        if b.first is not None:
            arm = at - self.centre(b)
            Q[b.first:b.first + 2] = force
            Q[b.first + 2] = arm[0] * force[1] - arm[1] * force[0]
        return Q

    def mass_diagonal(self) -> ca.SX:
        out = []
        for b in self.bodies.values():
            if b.first is not None:
                out += [b.mass, b.mass, b.inertia]
        return ca.vertcat(*out)

    def gravity_energy(self, gravity: ca.SX) -> ca.SX:
        V = ca.SX(0)
        for b in self.bodies.values():
            if b.first is not None:
                V -= b.mass * ca.dot(gravity, self.centre(b))
        return V


def _drives(book: ParameterBook) -> dict[str, ca.SX]:
    """Per body with a prescribed displacement (a `displacement` load), its [dx, dy, rotation]
    as numbers of the book; a component left out is held at 0 (the body is driven, not free)."""
    out = {}
    for name, load in book.document.loads.items():
        if load.type != "displacement":
            continue
        base = f"/loads/{name}"
        if load.body in out:
            raise MechanismError(f"{base}/body", f"body '{load.body}' has two prescribed displacements")
        parts = []
        for field, kind in (("dx", "length"), ("dy", "length"), ("rotation", "angle")):
            value = getattr(load, field)
            parts.append(book.number(f"{base}/{field}", value if value is not None else 0.0, kind))
        out[load.body] = ca.vertcat(*parts)
    return out
