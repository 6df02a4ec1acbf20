"""The impact model's coordinates of a document's bodies, and the bodies' energies in them.

Coordinates q = (x, y, theta) per free body: the displacement of its mass centre from the
drawn pose and its rotation, so that the mass matrix is diagonal and constant (the impact
laws and Moreau's step rely on it); a driven body (a `displacement` load) follows its
prescribed displacement, a fixed one stays. This module maps q to the bodies' points and to
their displacements.

The bodies themselves are the statics' (models.graph.collect, models.graph.loads): their numbers, their
kinetic energy (hence the mass matrix), and the potential of gravity and of the loads are
written once there, and evaluated here at the bodies' displacements in SI: every statics
parameter is the book's symbol under the same pointer (parameters_of), so each number stays a
symbol of the book that sensitivities and studies see."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from flexmech.models.errors import MechanismError
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.loads import kinetic_energy, load_potential
from flexmech.models.graph.planar import rot
from flexmech.models.impacts.book import ParameterBook

NOT_SECTIONS = {
    "loads": {},
    "outputs": {},
    "contacts": None,
    "simulate": None,
    "sweep": None,
    "inverse": None,
    "optimize": None,
}  # what the elements' energies never read


@dataclass
class Body:
    name: str
    first: int | None  # index of x in q; None for a fixed or driven body
    position: ca.SX  # drawn reference point
    angle: ca.SX
    centre_offset: ca.SX  # mass centre from the reference point, body axes
    drive: ca.SX | None = None  # a driven body's displacement [dx, dy, rotation] (a prescribed motion)


def parameters_of(rb: BodyCoordinates, mech, scaled: bool = True) -> ca.SX:
    """The statics parameters of `mech` as the book's SI symbols, divided by their kinds' scales
    (the statics' nondimensional vector) unless `scaled` is False."""
    book = rb.book
    out = []
    for parameter, si in zip(mech.parameters, mech.si_values):
        kind = parameter.kind
        unit = (mech.doc_unit(kind), mech.doc_factor(kind)) if kind != "dimensionless" else ("1", 1.0)
        symbol = book.add(parameter.pointer, float(si), None, unit)
        out.append(symbol / mech.scales.of(kind) if scaled else symbol)
    return ca.vertcat(*out) if out else ca.SX(0, 1)


class BodyCoordinates:
    def __init__(self, book: ParameterBook):
        from flexmech.models.graph.mechanism import compile_mechanism

        self.book = book
        doc = book.document
        driven = _drives(book)
        moving = [name for name, body in doc.bodies.items() if name not in driven and not body.fixed]
        for name in moving:
            _check_inertia(book, name, doc.bodies[name])
        # the statics of the bodies, their loads and gravity; the impact pairs and flexures hold them
        bodies_only = doc.model_copy(update={**NOT_SECTIONS, "loads": doc.loads, "elements": {}})
        self.statics = compile_mechanism(bodies_only, grounded=False)
        self.si = AssemblyContext(self.statics.structure, parameters_of(self, self.statics, scaled=False))
        self.bodies: dict[str, Body] = {}
        n = 0
        for b, name in enumerate(self.statics.structure.bodies):
            body, base = doc.bodies[name], f"/bodies/{name}"
            position, angle = self.si.reference(b)
            offset = self.si.P.vec(f"{base}/center_of_mass") if body.center_of_mass is not None else ca.SX.zeros(2)
            self.bodies[name] = Body(name, n if name in moving else None, position, angle, offset, driven.get(name))
            n += 3 if name in moving else 0
        if n == 0:
            raise MechanismError("/bodies", "every body is fixed: nothing moves")
        self.size = n
        self.q = ca.SX.sym("q", n)
        self.v = ca.SX.sym("v", n)

    # ---- points -----------------------------------------------------------------------------------
    def body(self, name: str | None, pointer: str) -> Body:
        """The body `name`; None is the world, fixed at the origin (an object given without
        a body is in global axes and never moves)."""
        if name is None:
            return Body("world", None, ca.SX.zeros(2), ca.SX(0), ca.SX.zeros(2))
        if name not in self.bodies:
            raise MechanismError(pointer, f"unknown body '{name}' (bodies: {', '.join(self.bodies)})")
        return self.bodies[name]

    def centre(self, b: Body) -> ca.SX:
        """Mass centre, global (a driven body turns about its reference point)."""
        if b.drive is not None:
            return b.position + b.drive[:2] + rot(b.angle + b.drive[2]) @ b.centre_offset
        drawn = b.position + rot(b.angle) @ b.centre_offset
        return drawn if b.first is None else drawn + self.q[b.first : b.first + 2]

    def turn(self, b: Body) -> ca.SX:
        return b.angle + self.rotation(b)

    def rotation(self, b: Body) -> ca.SX:
        if b.drive is not None:
            return b.drive[2]
        return ca.SX(0) if b.first is None else self.q[b.first + 2]

    def point(self, b: Body, offset: ca.SX) -> ca.SX:
        """A point given in the body's axes from its reference point, global."""
        if b.first is None and b.drive is None:
            return self.book.hoist(b.position + rot(b.angle) @ offset)
        return self.centre(b) + rot(self.turn(b)) @ (offset - b.centre_offset)

    def body_offset(self, b: Body, at: ca.SX) -> ca.SX:
        """The body-axes offset of a point given globally in the drawn pose."""
        return rot(b.angle).T @ (at - b.position)

    def drawn_point(self, b: Body, at: ca.SX) -> ca.SX:
        """A point given globally in the drawn pose, carried by the body."""
        return self.point(b, self.body_offset(b, at))

    def wrench(self, b: Body, at: ca.SX, force: ca.SX) -> ca.SX:
        """Generalized force (n) of `force` applied at the global point `at` of body b."""
        Q = ca.SX.zeros(self.size)
        if b.first is not None:
            arm = at - self.centre(b)
            Q[b.first : b.first + 2] = force
            Q[b.first + 2] = arm[0] * force[1] - arm[1] * force[0]
        return Q

    # ---- the statics' bodies at q -------------------------------------------------------------------
    def displacement(self, name: str) -> ca.SX:
        """[dx, dy, rotation] of the body's reference point from its drawn pose (SI)."""
        body = self.bodies[name]
        if body.drive is not None:
            return body.drive
        if body.first is None:
            return ca.SX.zeros(3)
        return ca.vertcat(self.point(body, ca.SX.zeros(2)) - body.position, self.rotation(body))

    def displacements(self) -> list[ca.SX]:
        """Per body of the statics (its order), its displacement at q."""
        return [self.displacement(name) for name in self.statics.structure.bodies]

    def velocities(self) -> list[ca.SX]:
        """Per body of the statics, [vx, vy, omega] of its reference point at (q, v) (zero for a
        fixed or driven body: its motion is an input, not part of the model's kinetic energy)."""
        out = []
        for name in self.statics.structure.bodies:
            body = self.bodies[name]
            if body.first is None:
                out.append(ca.SX.zeros(3))
            else:
                out.append(ca.jtimes(self.displacement(name), self.q, self.v))
        return out

    def mass_diagonal(self) -> ca.SX:
        """The constant diagonal mass matrix of q: the Hessian in v of the statics' kinetic energy
        (models.graph.loads.kinetic_energy), which mass-centre coordinates make diagonal and free of q."""
        T = kinetic_energy(self.si, self.displacements(), self.velocities())
        hessian = ca.substitute(ca.hessian(T, self.v)[0], self.q, ca.SX.zeros(self.size))
        return ca.diag(hessian)

    def load_potential(self) -> ca.SX:
        """Minus the work of gravity on the bodies with mass and of the force and moment loads,
        from the drawn pose (models.graph.loads.load_potential), at q."""
        return load_potential(self.si, self.displacements())


def _check_inertia(book: ParameterBook, name: str, body) -> None:
    base = f"/bodies/{name}"
    if body.mass is None:
        raise MechanismError(
            f"{base}/mass",
            f"body '{name}' moves and has no mass: an impact simulation needs every free body's mass and inertia",
        )
    if body.inertia is None:
        raise MechanismError(
            f"{base}/inertia",
            f"body '{name}' moves and has no inertia: give its moment of inertia about its reference point",
        )
    book.number(f"{base}/mass", body.mass, "mass", "positive")
    book.number(f"{base}/inertia", body.inertia, "inertia", "positive")


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
