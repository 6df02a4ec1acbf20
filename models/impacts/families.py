"""A document's elements in an impact model, each from its own family (models.elements):

  energies    a family without an impact hook and without unknowns of its own (a spring, or a
              family registered later) takes part with the strain energy its energy form writes
              for the statics (energy_terms), evaluated at the bodies' poses;
  flexures    a family with an impact_flexure hook (the curved beams' closed form, seed 000) or
              an element with unknowns of its own, condensed from its statics
              (models.impacts.condensed): (1/2 psi.K.psi, psi, K);
  joints      a family with an impact_constraint hook (pin, slider): rows of g(q, t) = 0.

So the physics of an element is written once, in its own module, and statics, link dynamics
and impacts all use it. The statics works in nondimensional numbers (models.graph.mechanism.Scales);
the impact model in SI symbols of its book: each statics parameter becomes its book symbol
divided by its kind's scale, each body's displacement its reference point's and its rotation,
so the energy's value in SI is the statics energy times the energy scale."""

from __future__ import annotations

import casadi as ca

from flexmech.models.elements import FAMILIES
from flexmech.models.elements.base import NoEnergyForm
from flexmech.models.errors import MechanismError
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.planar import rot
from flexmech.models.impacts.condensed import condensed_flexure
from flexmech.models.impacts.coordinates import NOT_SECTIONS, BodyCoordinates, parameters_of


def bridged(element) -> bool:
    """Whether an element enters an impact model by its statics (no hook of its own)."""
    family = FAMILIES.named(element.type)
    if hasattr(family, "impact_by_statics") and family.impact_by_statics(element):
        return True
    return not any(hasattr(family, hook) for hook in ("impact_flexure", "impact_constraint"))


def element_energy(rb: BodyCoordinates) -> tuple[ca.SX, str, tuple[str, ...]]:
    """The strain energy (SI) of every bridged element of rb's document without unknowns of its
    own, at the bodies' poses; what shapes its graph (the elements' topologies: a spring's law
    is one); and the bridged elements with unknowns of their own (flexures() condenses them)."""
    from flexmech.models.graph.mechanism import compile_mechanism

    doc = rb.book.document
    names = [name for name, element in doc.elements.items() if bridged(element)]
    if not names:
        return ca.SX(0), "", ()
    own = doc.model_copy(update={**NOT_SECTIONS, "elements": {name: doc.elements[name] for name in names}})
    mech = compile_mechanism(own, grounded=False)  # the other elements and the impact pairs hold the bodies
    scales, structure = mech.scales, mech.structure
    ctx = AssemblyContext(structure, parameters_of(rb, mech))
    d = [rb.displacement(name) / ca.vertcat(scales.length, scales.length, 1) for name in structure.bodies]
    total = ca.SX(0)
    for topology in structure.elements:
        if not topology.unknowns:
            total += _energy(ctx, topology, d, doc.elements[topology.name].type)
    condensed = tuple(topology.name for topology in structure.elements if topology.unknowns)
    return total * scales.of("energy"), "|".join(repr(topology) for topology in structure.elements), condensed


def _energy(ctx: AssemblyContext, topology, d: list[ca.SX], element_type: str) -> ca.SX:
    pointer = f"/elements/{topology.name}/type"
    refused = f"a {element_type} element is not part of impact simulations"
    rigid = "impact simulations take rigid bodies and the massless elements between them"
    try:
        terms = FAMILIES.of(topology).energy_terms(ctx, topology, d)
    except NoEnergyForm as why:
        raise MechanismError(pointer, f"{refused}: {why}") from None
    if terms.variables is not None or terms.equalities or terms.inequalities:
        raise MechanismError(pointer, f"{refused}: its energy has variables or constraints of its own, and {rigid}")
    if terms.inertia:
        raise MechanismError(pointer, f"{refused} with its mass ({rigid}): leave out its density")
    return terms.energy


def flexures(rb: BodyCoordinates, condensed: tuple[str, ...]) -> list[tuple[str, ca.SX, ca.SX, ca.SX]]:
    """(name, 1/2 psi.K.psi, psi, K) of every flexure: the elements whose family has an
    impact_flexure hook and those condensed from their statics (`condensed`)."""
    out = []
    for name, element in rb.book.document.elements.items():
        family = FAMILIES.named(element.type)
        if name in condensed:
            out.append((name, *condensed_flexure(rb, name)))
        elif hasattr(family, "impact_flexure"):
            out.append((name, *family.impact_flexure(rb, name, element)))
    return out


def turning_force(rb: BodyCoordinates, flexures: list) -> ca.SX:
    """The generalized force of the flexures whose stiffness turns with the end body relative to
    the start body (seed 004, Eq. 8): K becomes A3 K A3' with A3 that relative rotation, so the
    force -(d psi/dq)' A3 K A3' psi has no potential."""
    doc = rb.book.document
    Q = ca.SX.zeros(rb.size)
    for name, _, psi, K in flexures:
        element = doc.elements[name]
        i = rb.body(element.from_, f"/elements/{name}/from")
        j = rb.body(element.to, f"/elements/{name}/to")
        A3 = ca.diagcat(rot(rb.rotation(j) - rb.rotation(i)), ca.SX(1))
        Q -= ca.mtimes(ca.jacobian(psi, rb.q).T, A3 @ K @ A3.T @ psi)
    return Q


def joint_constraints(rb: BodyCoordinates) -> tuple[ca.SX, list[str], list[tuple]]:
    """(g stacked over the joints, their names, per joint its multipliers' (label, kind)): a
    pin keeps a point of its two bodies together (lambda its force on `to`), a slider lets
    `to` slide along an axis of `from` without turning (lambda its force across the axis and
    its couple)."""
    rows, names, labels = [], [], []
    for name, element in rb.book.document.elements.items():
        family = FAMILIES.named(element.type)
        if not hasattr(family, "impact_constraint"):
            continue
        g, named = family.impact_constraint(rb, name, element)
        rows.append(g)
        names.append(name)
        labels.append(named)
    return (ca.vertcat(*rows) if rows else ca.SX(0, 1)), names, labels
