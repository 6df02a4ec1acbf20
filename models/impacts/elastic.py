"""Elements in an impact model through their statics energy: a family that brings no impact
hook of its own (a spring, or a family registered later) and has no unknowns of its own takes
part with the strain energy its energy form writes for the statics (models.elements.base:
energy_terms), evaluated at the rigid bodies' poses. So the physics of such an element is
written once, in its own module, and statics, link dynamics and impacts all use it. Elements
with unknowns of their own (links) are named for models.impacts.condensed.

The statics works in nondimensional numbers (models.mechanism.Scales); the impact model in
SI symbols of its book. Each statics parameter becomes its book symbol divided by its kind's
scale, each body's displacement its reference point's and its rotation, so the energy's value
in SI is the statics energy times the energy scale, and every number stays a symbol of the
book (sensitivities and studies see it)."""

from __future__ import annotations

import casadi as ca

from models.context import AssemblyContext
from models.elements import FAMILIES
from models.elements.base import NoEnergyForm
from models.errors import MechanismError
from models.impacts.bodies import RigidBodies

NOT_SECTIONS = {"loads": {}, "outputs": {}, "contacts": None, "simulate": None, "sweep": None, "inverse": None,
                "optimize": None}  # what the elements' energies never read


def bridged(element) -> bool:
    """Whether an element enters an impact model by its statics energy (no hook of its own)."""
    family = FAMILIES.named(element.type)
    if hasattr(family, "impact_by_statics") and family.impact_by_statics(element):
        return True
    return not any(hasattr(family, hook) for hook in ("impact_flexure", "impact_constraint"))


def element_energy(rb: RigidBodies) -> tuple[ca.SX, str, tuple[str, ...]]:
    """The strain energy (SI) of every bridged element of rb's document without unknowns of its
    own, at the bodies' poses; what shapes its graph (the elements' topologies: a spring's law
    is one); and the bridged elements with unknowns of their own (models.impacts.condensed
    takes them)."""
    from models.mechanism import compile_mechanism

    doc = rb.book.document
    names = [name for name, element in doc.elements.items() if bridged(element)]
    if not names:
        return ca.SX(0), "", ()
    own = doc.model_copy(update={**NOT_SECTIONS, "elements": {name: doc.elements[name] for name in names}})
    mech = compile_mechanism(own)
    scales, structure = mech.scales, mech.structure
    ctx = AssemblyContext(structure, parameters_of(rb, mech))
    d = [_displacement(rb, name) / ca.vertcat(scales.length, scales.length, 1) for name in structure.bodies]
    total = ca.SX(0)
    for topology in structure.elements:
        if not topology.unknowns:
            total += _energy(ctx, topology, d, doc.elements[topology.name].type)
    condensed = tuple(topology.name for topology in structure.elements if topology.unknowns)
    return total * scales.of("energy"), "|".join(repr(topology) for topology in structure.elements), condensed


def parameters_of(rb: RigidBodies, mech, scaled: bool = True) -> ca.SX:
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


def _displacement(rb: RigidBodies, name: str) -> ca.SX:
    """[dx, dy, rotation] of the body's reference point from its drawn pose (SI)."""
    body = rb.bodies[name]
    if body.drive is not None:
        return body.drive
    if body.first is None:
        return ca.SX.zeros(3)
    return ca.vertcat(rb.point(body, ca.SX.zeros(2)) - body.position, rb.rotation(body))


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
