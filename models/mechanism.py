"""Compile a mechanism document into a Mechanism: structure, parameters and CasADi graphs.

The structure (bodies, which coordinates are free, element topology and models, where loads
and outputs sit) decides the graphs; every number of the document is a parameter. Graphs are
built once per structure and cached by its hash, so changing a load, a section or a radius
never rebuilds anything. Parameters are passed nondimensionalized: lengths by the largest
flexure radius, forces by the largest flexure EI over that length squared, so a case in
(uN, mm) and its SI copy present the same numbers to the solver.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from models.document import (
    CurvedBeam,
    GeneralSection,
    Link,
    RectangularSection,
    SectionExpression,
    TaperedRectangularSection,
    ForceLoad,
    MechanismDocument,
    MomentLoad,
    PointOutput,
    PrescribedDisplacement,
    ReactionOutput,
)
from models.errors import MechanismError
from models.expression import compile_expression
from models.units import document_unit, quantity_to_si, unit_factor

COORDINATES = ("x", "y", "angle")
MODELS = ("linear", "partial_nonlinear", "exact")


@dataclass(frozen=True)
class Parameter:
    pointer: str
    kind: str  # length | force | moment | stress | angle
    check: str | None = None  # positive | arc_angle


@dataclass(frozen=True)
class FlexureTopology:
    name: str
    start_body: int  # body the arc starts on (after normalizing a clockwise arc)
    end_body: int
    reversed: bool  # document gave a clockwise arc: start/end swapped for the ccw model
    model: str
    material: str
    section: str


@dataclass(frozen=True)
class LinkTopology:
    """A distributed elastica: a `link` element, or a curved beam with the `exact` model."""

    name: str
    start_body: int
    end_body: int
    start: str  # clamped | pinned
    end: str
    shape: str  # straight | arc | polynomial | fourier_sine | expression | curved_beam
    terms: int  # number of shape coefficients
    expression: str | None
    omega: float | None
    located: str  # "at" | "reference" | "arc" (an exact curved beam: from its arc geometry)
    reversed: bool  # an exact curved beam given clockwise
    material: str
    section: str
    section_shape: str  # rectangle | tapered_rectangle | general
    I_expression: str | None
    A_expression: str | None
    shear: bool
    axial: bool
    intervals: int
    order: int

    @property
    def unknowns(self) -> int:
        """h, v, psi(0), m(0) and four states at each inner shooting node."""
        return 4 * self.intervals


@dataclass(frozen=True)
class LoadTopology:
    name: str
    kind: str  # force | moment
    body: int
    location: str  # reference | at | offset


@dataclass(frozen=True)
class PointTopology:
    name: str
    body: int
    location: str


@dataclass(frozen=True)
class Structure:
    """Everything that shapes the graphs; no numbers."""

    bodies: tuple[str, ...]
    parameters: tuple[Parameter, ...]
    # per body and coordinate: None if free, else the pointer of its prescribed value ("" = 0)
    prescribed: tuple[tuple[str | None, str | None, str | None], ...]
    flexures: tuple[FlexureTopology, ...]
    links: tuple[LinkTopology, ...]
    loads: tuple[LoadTopology, ...]
    points: tuple[PointTopology, ...]
    reactions: tuple[tuple[str, int], ...]
    length_unit_si: float = 1.0  # SI size of the document's length unit (section expressions use it)

    @cached_property
    def key(self) -> str:
        payload = json.dumps(_plain(self), sort_keys=True)
        return hashlib.sha256(payload.encode()).hexdigest()[:16]

    @cached_property
    def free(self) -> tuple[tuple[int, int], ...]:
        return tuple((b, c) for b, row in enumerate(self.prescribed) for c in range(3) if row[c] is None)

    @cached_property
    def link_offsets(self) -> tuple[int, ...]:
        """Where each link's unknowns start in z (after the free body coordinates)."""
        offsets, k = [], len(self.free)
        for link in self.links:
            offsets.append(k)
            k += link.unknowns
        return tuple(offsets)

    @cached_property
    def n_unknowns(self) -> int:
        return len(self.free) + sum(link.unknowns for link in self.links)

    @cached_property
    def index(self) -> dict[str, int]:
        return {p.pointer: i for i, p in enumerate(self.parameters)}

    def coordinate_name(self, body: int, coordinate: int) -> str:
        return f"{self.bodies[body]}.{COORDINATES[coordinate]}"


def _plain(obj: Any) -> Any:
    if hasattr(obj, "__dataclass_fields__"):
        return {k: _plain(getattr(obj, k)) for k in obj.__dataclass_fields__}
    if isinstance(obj, (tuple, list)):
        return [_plain(x) for x in obj]
    return obj


@dataclass(frozen=True)
class Scales:
    """SI size of one nondimensional unit of each kind of quantity."""

    length: float
    force: float

    def of(self, kind: str) -> float:
        return {
            "length": self.length,
            "force": self.force,
            "moment": self.force * self.length,
            "energy": self.force * self.length,
            "stress": self.force / self.length**2,
            "angle": 1.0,
            "stiffness": self.force / self.length,
            "area": self.length**2,
            "second_moment": self.length**4,
            "dimensionless": 1.0,
        }[kind]


class _Collector:
    """Walks a validated document: checks references and ranges, gathers parameters."""

    def __init__(self, doc: MechanismDocument):
        self.doc = doc
        self.parameters: list[Parameter] = []
        self.values: list[float] = []

    def unit_of(self, kind: str) -> str:
        return document_unit(self.doc.units, kind)

    def add(self, pointer: str, value, kind: str, check: str | None = None) -> None:
        si = quantity_to_si(value, kind, self.unit_of(kind), pointer)
        _check_value(pointer, si, check, self.doc.units)
        self.parameters.append(Parameter(pointer, kind, check))
        self.values.append(si)

    def add_vec(self, pointer: str, values, kind: str) -> None:
        for i, v in enumerate(values):
            self.add(f"{pointer}/{i}", v, kind)

    def body_index(self, name: str, pointer: str, bodies: list[str]) -> int:
        if name not in bodies:
            raise MechanismError(pointer, f"unknown body '{name}' (bodies: {', '.join(bodies)})")
        return bodies.index(name)


def _check_value(pointer: str, si: float, check: str | None, units) -> None:
    if not math.isfinite(si):
        raise MechanismError(pointer, "must be a finite number")
    if check == "positive" and si <= 0:
        raise MechanismError(pointer, f"must be positive, got {si:g} (SI)")
    if check == "poisson" and not (-1.0 < si <= 0.5):
        raise MechanismError(pointer, f"Poisson's ratio must lie in (-1, 0.5], got {si:g}")
    if check == "arc_angle" and not (0.0 < si < 2 * math.pi):
        deg = math.degrees(si)
        raise MechanismError(pointer, f"arc angle must lie in (0, 360) deg, got {deg:g} deg")


def _collect(doc: MechanismDocument, model_override: str | None) -> tuple[Structure, np.ndarray]:
    if model_override is not None and model_override not in MODELS:
        raise MechanismError("model", f"unknown model '{model_override}' (choose from {', '.join(MODELS)})")
    c = _Collector(doc)
    bodies = list(doc.bodies)
    if not bodies:
        raise MechanismError("/bodies", "a mechanism needs at least one body")

    for name, body in doc.bodies.items():
        c.add_vec(f"/bodies/{name}/position", body.position, "length")
        c.add(f"/bodies/{name}/angle", body.angle, "angle")

    prescribed: list[list[str | None]] = [["" if b.fixed else None] * 3 for b in doc.bodies.values()]
    for name, load in doc.loads.items():
        if not isinstance(load, PrescribedDisplacement):
            continue
        b = c.body_index(load.body, f"/loads/{name}/body", bodies)
        for coord, (field_name, kind) in enumerate((("dx", "length"), ("dy", "length"), ("rotation", "angle"))):
            value = getattr(load, field_name)
            if value is None:
                continue
            pointer = f"/loads/{name}/{field_name}"
            if prescribed[b][coord]:
                raise MechanismError(pointer, f"{bodies[b]}.{COORDINATES[coord]} is already prescribed by {prescribed[b][coord]}")
            c.add(pointer, value, kind)
            prescribed[b][coord] = pointer
    if not any(all(v is not None for v in row) for row in prescribed):
        raise MechanismError("/bodies", 'no fixed body: mark at least one body "fixed": true (or prescribe all its motions)')

    used_materials: set[str] = set()
    shear_materials: set[str] = set()
    used_sections: dict[str, str] = {}  # section -> pointer of its first user
    flexures: list[FlexureTopology] = []
    links: list[LinkTopology] = []
    rotational: list[int] = [0] * len(bodies)  # connections that can carry a moment, per body
    for name, el in doc.elements.items():
        base = f"/elements/{name}"
        i = c.body_index(el.from_, f"{base}/from", bodies)
        j = c.body_index(el.to, f"{base}/to", bodies)
        if i == j:
            raise MechanismError(f"{base}/to", f"an element must join two different bodies (both ends on '{el.to}')")
        if el.material not in doc.materials:
            raise MechanismError(f"{base}/material", f"unknown material '{el.material}' (materials: {', '.join(doc.materials) or 'none'})")
        if el.section not in doc.sections:
            raise MechanismError(f"{base}/section", f"unknown section '{el.section}' (sections: {', '.join(doc.sections) or 'none'})")
        used_materials.add(el.material)
        used_sections.setdefault(el.section, f"{base}/section")
        section = doc.sections[el.section]
        if isinstance(el, CurvedBeam):
            if not isinstance(section, RectangularSection):
                raise MechanismError(f"{base}/section", f"a curved beam needs a rectangle section ('{el.section}' is {section.shape})")
            c.add_vec(f"{base}/center", el.center, "length")
            c.add(f"{base}/radius", el.radius, "length", "positive")
            c.add(f"{base}/start_angle", el.start_angle, "angle")
            c.add(f"{base}/arc_angle", el.arc_angle, "angle", "arc_angle")
            reversed_ = el.direction == "cw"
            start, end = (j, i) if reversed_ else (i, j)
            model = model_override or el.model
            rotational[i] += 1
            rotational[j] += 1
            if model == "exact":
                if el.order % 2:
                    raise MechanismError(f"{base}/order", f"the integration order must be even, got {el.order}")
                links.append(LinkTopology(name, start, end, "clamped", "clamped", "curved_beam", 0, None, None,
                                          "arc", reversed_, el.material, el.section, "rectangle", None, None,
                                          False, False, el.intervals, el.order))
            else:
                flexures.append(FlexureTopology(name, start, end, reversed_, model, el.material, el.section))
        elif isinstance(el, Link):
            links.append(_collect_link(c, name, el, i, j, section))
            rotational[i] += el.start == "clamped"
            rotational[j] += el.end == "clamped"
            if el.shear:
                shear_materials.add(el.material)
    for name in sorted(used_materials):
        material = doc.materials[name]
        c.add(f"/materials/{name}/E", material.E, "stress", "positive")
        if name in shear_materials:
            if material.G is not None:
                c.add(f"/materials/{name}/G", material.G, "stress", "positive")
            elif material.nu is not None:
                c.add(f"/materials/{name}/nu", material.nu, "dimensionless", "poisson")
            else:
                raise MechanismError(f"/materials/{name}/G", "a link with shear needs the shear modulus G or Poisson's ratio nu")
    needs_area = {link.section for link in links if link.shear or link.axial}
    for name in sorted(used_sections):
        _collect_section(c, name, doc.sections[name], name in needs_area)

    _reduce_pinned_joints(doc, bodies, prescribed, rotational)
    _check_grounded(doc, bodies, prescribed)

    loads: list[LoadTopology] = []
    for name, load in doc.loads.items():
        base = f"/loads/{name}"
        if isinstance(load, ForceLoad):
            b = c.body_index(load.body, f"{base}/body", bodies)
            c.add_vec(f"{base}/force", load.force, "force")
            location = _locate(c, base, load)
            loads.append(LoadTopology(name, "force", b, location))
        elif isinstance(load, MomentLoad):
            b = c.body_index(load.body, f"{base}/body", bodies)
            c.add(f"{base}/moment", load.moment, "moment")
            loads.append(LoadTopology(name, "moment", b, "reference"))

    points: list[PointTopology] = []
    reactions: list[tuple[str, int]] = []
    for name, out in doc.outputs.items():
        base = f"/outputs/{name}"
        if "." in name:
            raise MechanismError(base, "output names may not contain '.' (it separates the quantity, as in ee.x)")
        b = c.body_index(out.body, f"{base}/body", bodies)
        if isinstance(out, PointOutput):
            points.append(PointTopology(name, b, _locate(c, base, out)))
        elif isinstance(out, ReactionOutput):
            if all(v is None for v in prescribed[b]):
                raise MechanismError(f"{base}/body", f"body '{out.body}' is neither fixed nor has a prescribed motion, so it has no reaction")
            reactions.append((name, b))

    structure = Structure(
        bodies=tuple(bodies),
        parameters=tuple(c.parameters),
        prescribed=tuple(tuple(row) for row in prescribed),
        flexures=tuple(flexures),
        links=tuple(links),
        loads=tuple(loads),
        points=tuple(points),
        reactions=tuple(reactions),
        length_unit_si=unit_factor(document_unit(doc.units, "length"), "length", "/units/length"),
    )
    return structure, np.array(c.values, dtype=float)


def _collect_link(c: _Collector, name: str, el: Link, i: int, j: int, section) -> LinkTopology:
    base = f"/elements/{name}"
    if el.order % 2:
        raise MechanismError(f"{base}/order", f"the integration order must be even, got {el.order}")
    c.add(f"{base}/length", el.length, "length", "positive")
    located = "reference"
    if el.at is not None:
        if c.doc.bodies[el.from_].joint:
            raise MechanismError(f"{base}/at", f"a link starts at its joint's position: leave 'at' out for joint '{el.from_}'")
        c.add_vec(f"{base}/at", el.at, "length")
        located = "at"
    shape = el.shape
    sbase = f"{base}/shape"
    terms, expression, omega = 0, None, None
    if shape.type in ("straight", "arc", "fourier_sine"):
        c.add(f"{sbase}/angle", shape.angle, "angle")
    if shape.type == "arc":
        c.add(f"{sbase}/sweep", shape.sweep, "angle")
    if shape.type in ("polynomial", "fourier_sine"):
        terms = len(shape.coefficients)
        for k, value in enumerate(shape.coefficients):
            c.add(f"{sbase}/coefficients/{k}", value, "dimensionless")
    if shape.type == "fourier_sine":
        omega = float(shape.omega)
    if shape.type == "expression":
        compile_expression(shape.expression, f"{sbase}/expression")
        expression = shape.expression
    if (el.shear or el.axial) and isinstance(section, GeneralSection) and section.A is None:
        raise MechanismError(f"/sections/{el.section}/A", f"the area is required: link '{name}' has "
                             f"{'shear' if el.shear else 'axial'} strain")
    I_expr = A_expr = None
    if isinstance(section, GeneralSection):
        I_expr = section.I.expression if isinstance(section.I, SectionExpression) else None
        A_expr = section.A.expression if isinstance(section.A, SectionExpression) else None
    return LinkTopology(name, i, j, el.start, el.end, shape.type, terms, expression, omega, located, False,
                        el.material, el.section, section.shape, I_expr, A_expr, el.shear, el.axial,
                        el.intervals, el.order)


def _collect_section(c: _Collector, name: str, section, needs_area: bool) -> None:
    base = f"/sections/{name}"
    if isinstance(section, RectangularSection):
        c.add(f"{base}/b", section.b, "length", "positive")
        c.add(f"{base}/h", section.h, "length", "positive")
    elif isinstance(section, TaperedRectangularSection):
        c.add(f"{base}/b", section.b, "length", "positive")
        c.add(f"{base}/h_start", section.h_start, "length", "positive")
        c.add(f"{base}/h_end", section.h_end, "length", "positive")
    else:
        for field_name, kind in (("I", "second_moment"), ("A", "area")):
            value = getattr(section, field_name)
            if isinstance(value, SectionExpression):
                compile_expression(value.expression, f"{base}/{field_name}/expression")
                if "/units/length" not in {p.pointer for p in c.parameters}:
                    c.add("/units/length", 1.0, "length")  # one document length unit, for expressions
            elif value is not None:
                c.add(f"{base}/{field_name}", value, kind, "positive")
        if section.c is not None:
            c.add(f"{base}/c", section.c, "length", "positive")
    if section.shear_factor is not None:
        c.add(f"{base}/shear_factor", section.shear_factor, "dimensionless", "positive")


def _reduce_pinned_joints(doc: MechanismDocument, bodies: list[str], prescribed, rotational: list[int]) -> None:
    """A joint held only by pins has no rotation: its angle is not a coordinate."""
    for b, name in enumerate(bodies):
        body = doc.bodies[name]
        if not body.joint or body.fixed or rotational[b] or prescribed[b][2] is not None:
            continue
        for load_name, load in doc.loads.items():
            if load.body != name:
                continue
            if isinstance(load, MomentLoad) or (isinstance(load, ForceLoad) and (load.at or load.offset)):
                raise MechanismError(f"/loads/{load_name}", f"joint '{name}' is held only by pins, so it "
                                     "cannot take a moment: apply forces at the joint itself")
        prescribed[b][2] = ""


def _check_grounded(doc: MechanismDocument, bodies: list[str], prescribed) -> None:
    """Every body must reach a fixed one through elements, or nothing holds it."""
    neighbours: dict[str, set[str]] = {name: set() for name in bodies}
    for el in doc.elements.values():
        neighbours[el.from_].add(el.to)
        neighbours[el.to].add(el.from_)
    grounded = [name for b, name in enumerate(bodies) if all(v is not None for v in prescribed[b])]
    seen, stack = set(grounded), list(grounded)
    while stack:
        for other in neighbours[stack.pop()]:
            if other not in seen:
                seen.add(other)
                stack.append(other)
    for name in bodies:
        if name not in seen:
            what = "joint" if doc.bodies[name].joint else "body"
            raise MechanismError(f"/bodies/{name}", f"floating {what} '{name}' has no path to a fixed body "
                                 "through elements: connect it to ground by a link or a flexure, or fix it")


def _locate(c: _Collector, base: str, item) -> str:
    if item.at is not None:
        c.add_vec(f"{base}/at", item.at, "length")
        return "at"
    if item.offset is not None:
        c.add_vec(f"{base}/offset", item.offset, "length")
        return "offset"
    return "reference"


def _nominal_EI(structure: Structure, si: np.ndarray, material: str, section: str) -> float:
    """E times a representative I of a section (its largest along a taper, mid-length for an
    expression), for scaling only."""
    idx = structure.index
    E = si[idx[f"/materials/{material}/E"]]
    if f"/sections/{section}/h" in idx:
        return E * si[idx[f"/sections/{section}/b"]] * si[idx[f"/sections/{section}/h"]] ** 3 / 12
    if f"/sections/{section}/h_start" in idx:
        h = max(si[idx[f"/sections/{section}/h_start"]], si[idx[f"/sections/{section}/h_end"]])
        return E * si[idx[f"/sections/{section}/b"]] * h**3 / 12
    if f"/sections/{section}/I" in idx:
        return E * si[idx[f"/sections/{section}/I"]]
    return E * _expression_I_at_mid_length(structure, section)


def _expression_I_at_mid_length(structure: Structure, section: str) -> float:
    link = next(k for k in structure.links if k.section == section)
    u = ca.SX.sym("u")
    value = float(ca.Function("I", [u], [ca.SX(compile_expression(link.I_expression, "")(u))])(0.5))
    return value * structure.length_unit_si**4  # the expression is in document length units ^ 4


def _scales(structure: Structure, si: np.ndarray) -> Scales:
    idx = structure.index
    sizes, EIs = [], []
    for f in structure.flexures:
        sizes.append(si[idx[f"/elements/{f.name}/radius"]])
        EIs.append(_nominal_EI(structure, si, f.material, f.section))
    for link in structure.links:
        if link.shape == "curved_beam":
            sizes.append(si[idx[f"/elements/{link.name}/radius"]])
        else:
            sizes.append(si[idx[f"/elements/{link.name}/length"]])
        EIs.append(_nominal_EI(structure, si, link.material, link.section))
    if sizes:
        length = max(sizes)
        return Scales(length=length, force=max(EIs) / length**2)
    positions = [abs(si[i]) for i, p in enumerate(structure.parameters) if p.kind == "length"]
    length = max([x for x in positions if x > 0], default=1.0)
    return Scales(length=length, force=1.0)


@dataclass(frozen=True)
class Mechanism:
    """A compiled mechanism: its structure, parameter values (SI) and graphs.

    Unknowns z are the displacements of the free body coordinates from the undeformed pose
    (nondimensional: lengths / scales.length, angles in rad), in `structure.free` order.
    """

    document: MechanismDocument
    structure: Structure
    si_values: np.ndarray
    scales: Scales

    @property
    def parameters(self) -> tuple[Parameter, ...]:
        return self.structure.parameters

    @property
    def free_coordinates(self) -> list[str]:
        return [self.structure.coordinate_name(b, c) for b, c in self.structure.free]

    @property
    def n_free(self) -> int:
        """Number of unknowns z: free body coordinates, then the links' shooting unknowns."""
        return self.structure.n_unknowns

    @property
    def n_body_coordinates(self) -> int:
        return len(self.structure.free)

    @cached_property
    def graphs(self):
        from models.assembly import graphs_for

        return graphs_for(self.structure)

    # --- units -------------------------------------------------------------------------
    def doc_unit(self, kind: str) -> str:
        return document_unit(self.document.units, kind)

    def doc_factor(self, kind: str) -> float:
        """SI value of one document unit of `kind`."""
        return unit_factor(self.doc_unit(kind), kind, kind)

    def nd_per_doc(self, kind: str) -> float:
        """Nondimensional value of one document unit of `kind`."""
        return self.doc_factor(kind) / self.scales.of(kind)

    # --- parameters ----------------------------------------------------------------------
    def parameter_index(self, pointer: str) -> int:
        try:
            return self.structure.index[pointer]
        except KeyError:
            close = [p.pointer for p in self.parameters if p.pointer.startswith(pointer.rsplit("/", 1)[0])]
            hint = f" (numeric fields here: {', '.join(close[:8])})" if close else ""
            raise MechanismError(pointer, f"not a numeric field of this mechanism{hint}") from None

    def parameter_kind(self, pointer: str) -> str:
        return self.parameters[self.parameter_index(pointer)].kind

    def p(self) -> np.ndarray:
        """Nondimensional parameter vector."""
        kinds = np.array([self.scales.of(p.kind) for p in self.parameters])
        return self.si_values / kinds

    def with_values(self, overrides: dict[str, float | str]) -> "Mechanism":
        """A copy with numeric fields replaced; values in document units (or quantity strings)."""
        si = self.si_values.copy()
        for pointer, value in overrides.items():
            i = self.parameter_index(pointer)
            param = self.parameters[i]
            si[i] = quantity_to_si(value, param.kind, self.doc_unit(param.kind), pointer)
            _check_value(pointer, si[i], param.check, self.document.units)
        return replace(self, si_values=si)

    def value(self, pointer: str) -> float:
        """Current value of a numeric field, in document units."""
        i = self.parameter_index(pointer)
        return float(self.si_values[i] / self.doc_factor(self.parameters[i].kind))


def compile_mechanism(document: MechanismDocument, model: str | None = None) -> Mechanism:
    """Check a validated document and prepare its graphs (built lazily, cached by structure).

    `model` overrides the model of every curved beam ("linear" | "partial_nonlinear").
    """
    structure, si = _collect(document, model)
    return Mechanism(document=document, structure=structure, si_values=si, scales=_scales(structure, si))
