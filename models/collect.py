"""Walk a validated document into a Structure and its parameter values (SI).

Bodies, supports, loads and outputs are read here; every element is read by its family
(models.elements), which adds its numbers through the Collector and returns its topology.
Materials and sections are collected once each, for what their users need (E; G or nu for
shear; A for shear, axial strain and mass; the density for mass).
"""

from __future__ import annotations

import math

import numpy as np

from models.document import ForceLoad, MechanismDocument, MomentLoad, PointOutput, PrescribedDisplacement, ReactionOutput
from models.elements import FAMILIES, MODELS
from models.errors import MechanismError
from models.sections import collect_section
from models.structure import COORDINATES, InertiaTopology, LoadTopology, Parameter, PointTopology, Structure
from models.units import document_unit, quantity_to_si, unit_factor

DISPLACEMENT_FIELDS = (("dx", "length"), ("dy", "length"), ("rotation", "angle"))


def check_value(pointer: str, si: float, check: str | None) -> None:
    """A numeric field's physical range (SI value)."""
    if not math.isfinite(si):
        raise MechanismError(pointer, "must be a finite number")
    if check == "positive" and si <= 0:
        raise MechanismError(pointer, f"must be positive, got {si:g} (SI)")
    if check == "nonnegative" and si < 0:
        raise MechanismError(pointer, f"must not be negative, got {si:g} (SI)")
    if check == "poisson" and not (-1.0 < si <= 0.5):
        raise MechanismError(pointer, f"Poisson's ratio must lie in (-1, 0.5], got {si:g}")
    if check == "arc_angle" and not (0.0 < si < 2 * math.pi):
        deg = math.degrees(si)
        raise MechanismError(pointer, f"arc angle must lie in (0, 360) deg, got {deg:g} deg")


class Collector:
    """What a family reads a document section through: numbers become parameters (checked,
    in SI), references to bodies, materials and sections are checked and recorded."""

    def __init__(self, doc: MechanismDocument, model_override: str | None):
        self.doc = doc
        self.model_override = model_override
        self.bodies = list(doc.bodies)
        self.parameters: list[Parameter] = []
        self.values: list[float] = []
        self.notes: list[str] = []  # inputs the mechanism's models do not use, said aloud
        self.materials: dict[str, dict[str, bool]] = {}  # name -> needs (shear, density)
        self.sections: dict[str, bool] = {}  # name -> needs the area
        self.rotational = [0] * len(self.bodies)  # connections that can carry a moment, per body

    def unit_of(self, kind: str) -> str:
        return document_unit(self.doc.units, kind)

    def add(self, pointer: str, value, kind: str, check: str | None = None) -> None:
        si = quantity_to_si(value, kind, self.unit_of(kind), pointer)
        check_value(pointer, si, check)
        self.parameters.append(Parameter(pointer, kind, check))
        self.values.append(si)

    def add_vec(self, pointer: str, values, kind: str) -> None:
        for i, v in enumerate(values):
            self.add(f"{pointer}/{i}", v, kind)

    def unit_parameter(self, kind: str) -> str:
        """The parameter /units/<kind>: one document unit of `kind`, for safe expressions
        written in document units. Added once."""
        pointer = f"/units/{kind}"
        if pointer not in {p.pointer for p in self.parameters}:
            self.add(pointer, 1.0, kind)
        return pointer

    def body_index(self, name: str, pointer: str) -> int:
        if name not in self.bodies:
            raise MechanismError(pointer, f"unknown body '{name}' (bodies: {', '.join(self.bodies)})")
        return self.bodies.index(name)

    def use_material(self, name: str, pointer: str, shear: bool = False) -> None:
        if name not in self.doc.materials:
            raise MechanismError(pointer, f"unknown material '{name}' (materials: {', '.join(self.doc.materials) or 'none'})")
        needs = self.materials.setdefault(name, {"shear": False, "density": False})
        needs["shear"] |= shear

    def use_section(self, name: str, pointer: str, needs_area: bool = False):
        if name not in self.doc.sections:
            raise MechanismError(pointer, f"unknown section '{name}' (sections: {', '.join(self.doc.sections) or 'none'})")
        self.sections[name] = self.sections.get(name, False) or needs_area
        return self.doc.sections[name]

    def has_density(self, material: str, needs_area: bool, section: str) -> bool:
        """Whether an element of this material has mass; if so, the density (and, for a
        distributed element, the section's area) become parameters."""
        if self.doc.materials[material].density is None:
            return False
        self.materials[material]["density"] = True
        if needs_area:
            self.sections[section] = True
        return True

    def holds_rotation(self, body: int) -> None:
        """An element attached to `body` can carry a moment to it (a joint body held only by
        pins has no rotation)."""
        self.rotational[body] += 1

    def locate(self, base: str, item, at: str = "at", offset: str = "offset") -> str:
        """Where a point of a body is given: "at" (global), "offset" (body axes) or "reference"."""
        if getattr(item, at, None) is not None:
            self.add_vec(f"{base}/{at}", getattr(item, at), "length")
            return "at"
        if getattr(item, offset, None) is not None:
            self.add_vec(f"{base}/{offset}", getattr(item, offset), "length")
            return "offset"
        return "reference"


def collect(doc: MechanismDocument, model_override: str | None) -> tuple[Structure, np.ndarray, list[str]]:
    """The structure, its parameter values (SI) and notes on inputs that are not used."""
    if model_override is not None and model_override not in MODELS:
        raise MechanismError("model", f"unknown model '{model_override}' (choose from {', '.join(MODELS)})")
    if not doc.bodies:
        raise MechanismError("/bodies", "a mechanism needs at least one body")
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
    _collect_materials(c)
    for name in sorted(c.sections):
        collect_section(c, name, doc.sections[name], c.sections[name])
    _reduce_pinned_joints(c, prescribed)
    _check_grounded(c, prescribed)
    loads = _collect_loads(c)
    points, reactions = _collect_outputs(c, prescribed)
    structure = Structure(
        bodies=tuple(c.bodies), parameters=tuple(c.parameters), prescribed=tuple(tuple(row) for row in prescribed),
        elements=tuple(elements), loads=tuple(loads), points=tuple(points), reactions=tuple(reactions),
        masses=tuple(masses), gravity=doc.gravity is not None,
        length_unit_si=unit_factor(document_unit(doc.units, "length"), "length", "/units/length"))
    return structure, np.array(c.values, dtype=float), c.notes


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
                raise MechanismError(pointer, f"{c.bodies[b]}.{COORDINATES[coord]} is already prescribed by {prescribed[b][coord]}")
            c.add(pointer, value, kind)
            prescribed[b][coord] = pointer
    if not any(all(v is not None for v in row) for row in prescribed):
        raise MechanismError("/bodies", 'no fixed body: mark at least one body "fixed": true (or prescribe all its motions)')
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
                raise MechanismError(f"/materials/{name}/G", "a link with shear needs the shear modulus G or Poisson's ratio nu")
        if needs["density"]:
            c.add(f"/materials/{name}/density", material.density, "density", "nonnegative")
        elif material.density is not None:
            c.notes.append(f"material '{name}': its density is not used: the elements made of it "
                           "(curved beams with a constant-stiffness model) are massless")


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
                raise MechanismError(f"/loads/{load_name}", f"joint '{name}' is held only by pins, so it "
                                     "cannot take a moment: apply forces at the joint itself")
        prescribed[b][2] = ""


def _check_grounded(c: Collector, prescribed) -> None:
    """Every body must reach a fixed one through elements, or nothing holds it."""
    neighbours: dict[str, set[str]] = {name: set() for name in c.bodies}
    for el in c.doc.elements.values():
        neighbours[el.from_].add(el.to)
        neighbours[el.to].add(el.from_)
    grounded = [name for b, name in enumerate(c.bodies) if all(v is not None for v in prescribed[b])]
    seen, stack = set(grounded), list(grounded)
    while stack:
        for other in neighbours[stack.pop()]:
            if other not in seen:
                seen.add(other)
                stack.append(other)
    for name in c.bodies:
        if name not in seen:
            what = "joint" if c.doc.bodies[name].joint else "body"
            raise MechanismError(f"/bodies/{name}", f"floating {what} '{name}' has no path to a fixed body "
                                 "through elements: connect it to ground by a link or a flexure, or fix it")


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
                raise MechanismError(f"{base}/body", f"body '{out.body}' is neither fixed nor has a prescribed motion, so it has no reaction")
            reactions.append((name, b))
    return points, reactions
