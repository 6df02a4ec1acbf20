"""An impact model of a document: the rigid bodies' coordinates and constant diagonal mass,
the smooth generalized force, the energies, and the contact pairs, as CasADi expressions of
q, v and the parameter vector p (every number, SI; models.impacts.book).

Energies: kinetic T, elastic (the flexures' 1/2 psi.K.psi and the springs), gravity and
loads V_g. The smooth force is -grad(elastic + V_g) + Q_extra, where Q_extra is what the
flexure whose stiffness turns with the body adds (zero with the constant stiffness), so
T + elastic + V_g - (the WORKS: of contact and friction on the free bodies, of Q_extra, of
damping, and the inputs: loads that follow histories and the potential's explicit rate
under prescribed displacements) is constant. A prescribed displacement drives its body;
the histories enter as expressions of the time symbol t."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca

from flexmech.models.documents.document import MechanismDocument
from flexmech.models.errors import MechanismError
from flexmech.models.graph.planar import rot
from flexmech.models.impacts.book import ParameterBook
from flexmech.models.impacts.coordinates import BodyCoordinates
from flexmech.models.impacts.families import element_energy, joint_constraints, turning_force
from flexmech.models.impacts.families import flexures as flexures_of
from flexmech.models.impacts.pairs import PairModel, pair_model

DAMPING = "/simulate/damping"  # mass-proportional, as the link dynamics'; a parameter of the graphs
WORKS = ("contact_work", "friction_work", "flexure_work", "damping_work", "input_work")  # integrated with the motion
TIMED = ("/loads/", "/gravity/")  # the fields that may follow a history in time


@dataclass
class ImpactModel:
    book: ParameterBook
    bodies: BodyCoordinates
    pairs: list[PairModel]
    mass: ca.SX  # diagonal (n)
    force: ca.SX  # smooth generalized force (n), damping included, at time t
    extra: ca.SX  # Q_extra (n)
    damping: ca.SX  # -alpha M v (n)
    load_power: ca.SX  # of the loads that follow histories and of moving supports (the input)
    kinetic: ca.SX
    elastic: ca.SX
    gravity: ca.SX  # gravity and the constant loads
    turning: bool
    t: ca.SX
    history_key: str = ""
    constraints: ca.SX = None  # g(q, t) = 0 of the pins and sliders (2 rows each)
    joint_names: tuple[str, ...] = ()
    joint_labels: tuple[tuple, ...] = ()  # per joint its multipliers' (label, kind) (models.impacts.families)
    element_key: str = ""  # the topologies of the elements that enter by their statics energy

    @property
    def q(self) -> ca.SX:
        return self.bodies.q

    @property
    def v(self) -> ca.SX:
        return self.bodies.v

    @property
    def p(self) -> ca.SX:
        return self.book.symbols

    def constraint_rates(self) -> tuple[ca.SX, ca.SX, ca.SX]:
        """(G = dg/dq, the rate g_t at v = 0, gamma: d2g/dt2 less G a) of the pins."""
        g, q, v, t = self.constraints, self.q, self.v, self.t
        G = ca.jacobian(g, q)
        g_t = ca.jacobian(g, t)
        rate = ca.mtimes(G, v) + g_t
        gamma = ca.jtimes(rate, q, v) + ca.jacobian(rate, t)
        return G, g_t, gamma

    def coordinate_names(self) -> list[str]:
        return [
            f"{b.name}.{c}" for b in self.bodies.bodies.values() if b.first is not None for c in ("x", "y", "theta")
        ]

    def structure_key(self) -> str:
        """What decides the graphs (not the numbers)."""
        doc = self.book.document
        parts = [str(self.turning), ",".join(self.book.pointers), str(self.book.symbols.numel())]
        parts += [f"{b.name}:{b.first}" for b in self.bodies.bodies.values()]
        parts += [
            f"{e.type}:{getattr(e, 'kind', '')}:{getattr(e, 'direction', '')}:{getattr(e, 'at', 0) is None}"
            for e in doc.elements.values()
        ]
        parts += [
            f"{k}:{getattr(v, 'type', '')}:{getattr(v, 'offset', None) is None}:{getattr(v, 'at', None) is None}"
            for k, v in doc.loads.items()
        ]
        parts += [f"{p.name}:{p.law}:{p.friction}:{p.esdu is None}" for p in self.pairs]
        parts += [
            f"{k}:{s.type}:{getattr(s, 'body', None)}:{len(getattr(s, 'vertices', ()))}"
            for group in (doc.contacts.sites, doc.contacts.objects)
            for k, s in group.items()
        ]
        return "|".join(parts + [self.history_key, self.element_key])


def impact_model(
    document: MechanismDocument, histories: list[tuple[str, str, object]] = (), history_key: str = ""
) -> ImpactModel:
    """`histories`: (field pointer, where the history is given, t -> SI value as an SX) for
    the loads, gravity and prescribed displacements that change in time; `history_key` says
    what they are (they shape the graphs)."""
    if document.contacts is None or not document.contacts.pairs:
        raise MechanismError(
            "/contacts/pairs",
            "an impact simulation needs contact pairs: give the `contacts` section "
            "its sites (circles on bodies), objects and pairs",
        )
    book = ParameterBook(document)
    rb = BodyCoordinates(book)
    turning = document.simulate is not None and document.simulate.flexure_stiffness == "turning"
    springs, element_key, condensed = element_energy(rb)
    each_flexure = flexures_of(rb, condensed)
    flexures = sum((energy for _, energy, _, _ in each_flexure), ca.SX(0))
    elastic = flexures + springs
    gravity = rb.load_potential()  # and the constant loads
    pairs = [pair_model(rb, name, pair) for name, pair in document.contacts.pairs.items()]
    q, v, t = rb.q, rb.v, ca.SX.sym("t")
    extra = turning_force(rb, each_flexure) + ca.gradient(flexures, q) if turning else ca.SX.zeros(rb.size)
    mass = rb.mass_diagonal()
    alpha = document.simulate.damping if document.simulate is not None else 0.0
    damping = -book.add(DAMPING, alpha, "nonnegative", ("1/s", 1.0)) * mass * v
    loads, motions = _split(book, rb, histories, t)
    driven = _driver(motions)
    elastic, gravity, extra = driven(elastic), driven(gravity), driven(extra)
    for pair in pairs:
        _drive_pair(rb, pair, driven, t)
    timed = ca.vertcat(*[symbol for symbol, _ in loads]) if loads else ca.SX(0, 1)
    held = ca.substitute(gravity, timed, ca.SX.zeros(timed.shape))  # V is linear in loads and gravity
    acting = ca.substitute(gravity - held, timed, ca.vertcat(*[value for _, value in loads])) if loads else ca.SX(0)
    V = elastic + held
    power = -ca.dot(ca.gradient(acting, q), v) + ca.jacobian(V, t)  # timed loads; moving supports
    g, joints, labels = joint_constraints(rb)
    return ImpactModel(
        book,
        rb,
        pairs,
        mass,
        -ca.gradient(V + acting, q) + extra + damping,
        extra,
        damping,
        power,
        0.5 * ca.dot(mass * v, v),
        elastic,
        held,
        turning,
        t,
        history_key,
        driven(g),
        tuple(joints),
        tuple(labels),
        element_key,
    )


def _split(book: ParameterBook, rb: BodyCoordinates, histories, t) -> tuple[list, list]:
    """The histories' (symbol, value in t) pairs: loads and gravity, and prescribed motions."""
    motions = {
        f"/loads/{name}/{part}"
        for name, load in book.document.loads.items()
        if load.type == "displacement"
        for part in ("dx", "dy", "rotation")
    }
    loads, moving = [], []
    for pointer, where, history in histories:
        if not pointer.startswith(TIMED) or pointer not in book.pointers:
            raise MechanismError(
                where,
                f"{pointer} cannot change in time in an impact simulation: histories take "
                "the loads' force and moment components, gravity and prescribed displacements",
            )
        (moving if pointer in motions else loads).append((book.add(pointer, 0.0), history(t)))
    return loads, moving


def _driver(motions: list) -> Callable[[ca.SX], ca.SX]:
    """The substitution of the prescribed motions' (symbol, value in t) pairs into an expression."""
    moving_symbols = ca.vertcat(*[symbol for symbol, _ in motions]) if motions else ca.SX(0, 1)
    moving_values = ca.vertcat(*[value for _, value in motions]) if motions else ca.SX(0, 1)

    def driven(expr):  # the prescribed motions, in time
        return ca.substitute(expr, moving_symbols, moving_values) if motions else expr

    return driven


def _drive_pair(rb: BodyCoordinates, pair: PairModel, driven, t) -> None:
    """The pair's expressions in time, and the velocity at C that driven bodies add: each
    body's material point at C moves at J v plus its explicit rate in time."""
    for name in ("indentation", "normal_direction", "tangent_direction", "K", "point", "normal"):
        setattr(pair, name, driven(getattr(pair, name)))
    drift = ca.SX.zeros(2)
    for sign, body in zip((1, -1), pair.bodies):
        if body.drive is None:
            continue
        local = ca.SX.sym("local", 2)
        material = driven(rb.point(body, local))
        offset = rot(rb.turn(body)).T @ (pair.point - rb.centre(body)) + body.centre_offset
        drift += sign * ca.substitute(ca.jacobian(material, t), local, driven(offset))
    tangent = ca.vertcat(-pair.normal[1], pair.normal[0])
    pair.normal_drift, pair.tangent_drift = ca.dot(pair.normal, drift), ca.dot(tangent, drift)
