"""Walk a validated document into a Structure and its parameter values (SI).

Bodies, supports, loads and outputs are read here; every element is read by its family
(models.elements), which adds its numbers through the Collector and returns its topology.
Materials and sections are collected once each, for what their users need (E; G or nu for
shear; A for shear, axial strain and mass; the density for mass).
"""

from __future__ import annotations

import numpy as np

from flexmech.models.contact.collect_contacts import collect_contacts
from flexmech.models.documents.document import (
    ForceLoad,
    MechanismDocument,
    MomentLoad,
    PointOutput,
    PrescribedDisplacement,
    ReactionOutput,
)
from flexmech.models.documents.sections import collect_section
from flexmech.models.elements import FAMILIES, MODELS
from flexmech.models.errors import MechanismError, pointer_of
from flexmech.models.graph.collector import Collector
from flexmech.models.graph.structure import COORDINATES, InertiaTopology, LoadTopology, PointTopology, Structure
from flexmech.models.units import document_unit, unit_factor

DISPLACEMENT_FIELDS = (("dx", "length"), ("dy", "length"), ("rotation", "angle"))
MAX_NAME = 64
DOCUMENT_UNITS = (("length", "length"), ("force", "force"), ("stress", "stress"), ("angle", "angle"), ("mass", "mass"))


def collect(
    doc: MechanismDocument, model_override: str | None, grounded: bool = True
) -> tuple[Structure, np.ndarray, list[str]]:
    """The structure, its parameter values (SI) and notes on inputs that are not used;
    `grounded` False leaves out the check that every body reaches ground (for a part of a
    document whose other parts hold the bodies: an impact model's, models.impacts.coordinates)."""
    if model_override is not None and model_override not in MODELS:
        raise MechanismError("model", f"unknown model '{model_override}' (choose from {', '.join(MODELS)})")
    if not doc.bodies:
        raise MechanismError("/bodies", "a mechanism needs at least one body")
    _check_names(doc)
    for field_name, kind in DOCUMENT_UNITS:  # a bad unit is blamed on itself, not on a field using it
        unit_factor(getattr(doc.units, field_name), kind, f"/units/{field_name}")
    c = Collector(doc, model_override)
    masses = _collect_bodies(c)
    prescribed = _collect_supports(c)
    elements = []
    for name, el in doc.elements.items():
        base = f"/elements/{name}"
        i = c.body_index(el.from_, f"{base}/from")
        j = c.body_index(el.to, f"{base}/to")
        if i == j:
            raise MechanismError(f"{base}/to", f"an element must join two different bodies (both ends on '{el.to}')")
        elements.append(FAMILIES.named(el.type).collect(c, name, el, i, j))
    contacts = collect_contacts(c, doc.contacts, elements)
    _collect_materials(c)
    for name in sorted(c.sections):
        collect_section(c, name, doc.sections[name], c.sections[name])
    _reduce_pinned_joints(c, prescribed)
    if grounded:
        _check_grounded(c, prescribed)
    loads = _collect_loads(c)
    points, reactions = _collect_outputs(c, prescribed)
    structure = Structure(
        bodies=tuple(c.bodies),
        parameters=tuple(c.parameters),
        prescribed=tuple(tuple(row) for row in prescribed),
        elements=tuple(elements),
        loads=tuple(loads),
        points=tuple(points),
        reactions=tuple(reactions),
        masses=tuple(masses),
        gravity=doc.gravity is not None,
        contacts=contacts,
        length_unit_si=unit_factor(document_unit(doc.units, "length"), "length", "/units/length"),
    )
    return structure, np.array(c.values, dtype=float), c.notes


def _check_names(doc: MechanismDocument) -> None:
    """Names become parts of JSON pointers (/elements/<name>/radius): no '/' or '~' (RFC 6901
    would escape them, and every pointer would need it), no blanks, at most MAX_NAME characters."""
    named = [
        ((collection,), getattr(doc, collection))
        for collection in ("materials", "sections", "bodies", "elements", "loads", "outputs")
    ]
    if doc.contacts is not None:
        named += [(("contacts", part), getattr(doc.contacts, part)) for part in ("objects", "sites", "pairs")]
    for where, names in named:
        for name in names:
            pointer = pointer_of((*where, name))
            if not name.strip() or name != name.strip():
                raise MechanismError(pointer, "a name may not be empty or start or end with a blank")
            if "/" in name or "~" in name:
                raise MechanismError(pointer, "a name may not contain '/' or '~' (they are special in JSON pointers)")
            if len(name) > MAX_NAME:
                raise MechanismError(pointer, f"a name is at most {MAX_NAME} characters")


def _collect_bodies(c: Collector) -> list[InertiaTopology]:
    masses = []
    for b, (name, body) in enumerate(c.doc.bodies.items()):
        base = f"/bodies/{name}"
        c.add_vec(f"{base}/position", body.position, "length")
        c.add(f"{base}/angle", body.angle, "angle")
        if body.mass is None:
            for field_name in ("inertia", "center_of_mass"):
                if getattr(body, field_name) is not None:
                    raise MechanismError(f"{base}/mass", f"required with '{field_name}': give the body's mass")
            continue
        c.add(f"{base}/mass", body.mass, "mass", "nonnegative")
        if body.inertia is not None:
            c.add(f"{base}/inertia", body.inertia, "inertia", "nonnegative")
        if body.center_of_mass is not None:
            c.add_vec(f"{base}/center_of_mass", body.center_of_mass, "length")
        masses.append(InertiaTopology(b, body.inertia is not None, body.center_of_mass is not None))
    if c.doc.gravity is not None:
        c.add_vec("/gravity", c.doc.gravity, "acceleration")
    return masses


def _collect_supports(c: Collector) -> list[list[str | None]]:
    prescribed: list[list[str | None]] = [["" if b.fixed else None] * 3 for b in c.doc.bodies.values()]
    for name, load in c.doc.loads.items():
        if not isinstance(load, PrescribedDisplacement):
            continue
        b = c.body_index(load.body, f"/loads/{name}/body")
        for coord, (field_name, kind) in enumerate(DISPLACEMENT_FIELDS):
            value = getattr(load, field_name)
            if value is None:
                continue
            pointer = f"/loads/{name}/{field_name}"
            if prescribed[b][coord]:
                raise MechanismError(
                    pointer, f"{c.bodies[b]}.{COORDINATES[coord]} is already prescribed by {prescribed[b][coord]}"
                )
            c.add(pointer, value, kind)
            prescribed[b][coord] = pointer
    if not any(all(v is not None for v in row) for row in prescribed):
        raise MechanismError(
            "/bodies", 'no fixed body: mark at least one body "fixed": true (or prescribe all its motions)'
        )
    return prescribed


def _collect_materials(c: Collector) -> None:
    for name in sorted(c.materials):
        material, needs = c.doc.materials[name], c.materials[name]
        c.add(f"/materials/{name}/E", material.E, "stress", "positive")
        if needs["shear"]:
            if material.G is not None:
                c.add(f"/materials/{name}/G", material.G, "stress", "positive")
            elif material.nu is not None:
                c.add(f"/materials/{name}/nu", material.nu, "dimensionless", "poisson")
            else:
                raise MechanismError(
                    f"/materials/{name}/G", "a link with shear needs the shear modulus G or Poisson's ratio nu"
                )
        if needs["density"]:
            c.add(f"/materials/{name}/density", material.density, "density", "nonnegative")
        elif material.density is not None:
            c.notes.append(
                f"material '{name}': its density is not used: the elements made of it "
                "(curved beams with a constant-stiffness model) are massless"
            )


def _reduce_pinned_joints(c: Collector, prescribed) -> None:
    """A joint held only by pins has no rotation: its angle is not a coordinate."""
    for b, name in enumerate(c.bodies):
        body = c.doc.bodies[name]
        if not body.joint or body.fixed or c.rotational[b] or prescribed[b][2] is not None:
            continue
        for load_name, load in c.doc.loads.items():
            if load.body != name:
                continue
            if isinstance(load, MomentLoad) or (isinstance(load, ForceLoad) and (load.at or load.offset)):
                raise MechanismError(
                    f"/loads/{load_name}",
                    f"joint '{name}' is held only by pins, so it "
                    "cannot take a moment: apply forces at the joint itself",
                )
        prescribed[b][2] = ""


def _check_grounded(c: Collector, prescribed) -> None:
    """Every body must reach a fixed one through elements or contact pairs between bodies (a
    body in a clearance is held by the surface it rests on), or nothing holds it."""
    world = None  # an object given without a body is fixed in global axes: ground
    neighbours: dict[str | None, set[str | None]] = {name: set() for name in c.bodies}
    neighbours[world] = set()
    links = [(el.from_, el.to) for el in c.doc.elements.values()]
    contacts = c.doc.contacts
    if contacts is not None:
        ends = [
            (
                getattr(contacts.sites.get(pair.site), "body", None),
                getattr(contacts.objects.get(pair.object), "body", None),
            )
            for pair in contacts.pairs.values()
            if pair.site in contacts.sites and pair.object in contacts.objects
        ]
        # a site without a body is on a link (its ends' bodies are the link's business), never ground
        links += [(a, b) for a, b in ends if a is not None and a in neighbours and b in neighbours and a != b]
    for a, b in links:
        neighbours[a].add(b)
        neighbours[b].add(a)
    grounded = [world] + [name for b, name in enumerate(c.bodies) if all(v is not None for v in prescribed[b])]
    seen, stack = set(grounded), list(grounded)
    while stack:
        for other in neighbours[stack.pop()]:
            if other not in seen:
                seen.add(other)
                stack.append(other)
    for name in c.bodies:
        if name not in seen:
            what = "joint" if c.doc.bodies[name].joint else "body"
            raise MechanismError(
                f"/bodies/{name}",
                f"floating {what} '{name}' has no path to a fixed body "
                "through elements or impact pairs: connect it to ground by a link or a flexure, or fix it",
            )


def _collect_loads(c: Collector) -> list[LoadTopology]:
    loads = []
    for name, load in c.doc.loads.items():
        base = f"/loads/{name}"
        if isinstance(load, ForceLoad):
            b = c.body_index(load.body, f"{base}/body")
            c.add_vec(f"{base}/force", load.force, "force")
            loads.append(LoadTopology(name, "force", b, c.locate(base, load)))
        elif isinstance(load, MomentLoad):
            b = c.body_index(load.body, f"{base}/body")
            c.add(f"{base}/moment", load.moment, "moment")
            loads.append(LoadTopology(name, "moment", b, "reference"))
    return loads


def _collect_outputs(c: Collector, prescribed) -> tuple[list[PointTopology], list[tuple[str, int]]]:
    points, reactions = [], []
    for name, out in c.doc.outputs.items():
        base = f"/outputs/{name}"
        if "." in name:
            raise MechanismError(base, "output names may not contain '.' (it separates the quantity, as in ee.x)")
        b = c.body_index(out.body, f"{base}/body")
        if isinstance(out, PointOutput):
            points.append(PointTopology(name, b, c.locate(base, out)))
        elif isinstance(out, ReactionOutput):
            if all(v is None for v in prescribed[b]):
                raise MechanismError(
                    f"{base}/body",
                    f"body '{out.body}' is neither fixed nor has a prescribed motion, so it has no reaction",
                )
            reactions.append((name, b))
    return points, reactions
