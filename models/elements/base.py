"""The contract of an element family, and the registry of families.

A family is one element type of the document (`"type": "spring"`). It says:
  schema                       the pydantic model of its document section (with `type`, `from`, `to`)
  collect(c, name, el, i, j)   check the section, add its numbers to the parameters (through
                               the collector c), return its topology (an ElementTopology: no
                               numbers); i, j are the `from` and `to` body indices
  contribute(ctx, t, d, z)     its part of the residual form for body displacements d and its
                               own unknowns z (t.unknowns of them): a Contribution
  unknowns(t)                  (name, kind) of each of its own unknowns, in order
  energy_terms(ctx, t, d)      its part of the energy form (strain energy, equality and
                               inequality constraints, its own variables if it has any; its
                               unknowns are those variables, then the equalities'
                               multipliers), or raise NoEnergyForm saying why its model has none
  kinetic_energy(ctx, t, d, v) its kinetic energy for body displacements d and velocities v
                               (None: massless), or raise NoMassForm saying why its unknowns
                               cannot carry its mass (the mass form is the Hessian of the total)
  scale_hint(t, values)        sizes for nondimensionalizing (lengths, EI, stiffnesses)

Signs: a Contribution's `from_bodies[b]` is the wrench [Fx, Fy, M about b's reference point]
(global axes, nondimensional) that body b applies to the element: minus the element's force
on the body. The residual row of a free body coordinate is sum(from_bodies) - applied = 0.
For an element with an energy V(d) and constraints g(d) = 0 with multipliers lam (its
unknowns), from_bodies[b] = dV/dd_b + (dg/dd_b)^T lam and its rows are g: the residual form
is then the gradient of the Lagrangian, which tests check.
"""

from __future__ import annotations

import builtins
import inspect
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import casadi as ca
from pydantic import Field

from flexmech.models.documents.fields import Name, StrictModel
from flexmech.models.graph.structure import ElementTopology

if TYPE_CHECKING:
    from flexmech.models.graph.collector import Collector
    from flexmech.models.graph.context import AssemblyContext


class TwoBodyElement(StrictModel):
    """Every element joins body `from` to body `to`."""

    from_: Name = Field(alias="from")
    to: Name


@dataclass
class CentreLine:
    """Samples along an element for drawing and for contact: undeformed and deformed points
    (2-vectors, global, nondimensional) and, where the element is a solid of known thickness,
    the half thickness at each sample (its surfaces lie that far either side)."""

    deformed: list[ca.SX]
    undeformed: list[ca.SX]
    half_thickness: list[ca.SX] | None = None


@dataclass
class Contribution:
    from_bodies: dict[int, ca.SX]  # wrench each body applies to the element (3,)
    rows: ca.SX | None = None  # the element's own residual rows (as many as its unknowns)
    outputs: list[tuple[str, str, ca.SX]] = field(default_factory=list)  # (name, kind, value)
    energy: ca.SX | None = None  # strain energy, for reporting (models without an energy form too)
    centre_line: CentreLine | None = None
    merged: bool = False  # no common subexpression in from_bodies and rows is written twice


@dataclass
class EnergyTerms:
    """An element's part of the energy form. Its unknowns in the residual form are its own
    variables (if any), then the equalities' multipliers."""

    energy: ca.SX
    equalities: list[tuple[str, ca.SX]] = field(default_factory=list)  # g(d, q) = 0
    inequalities: list[tuple[str, ca.SX]] = field(default_factory=list)  # g(d, q) >= 0
    variables: ca.SX | None = None  # q: the element's own symbols (zero: undeformed), or None
    surfaces: Any = None  # where contact can touch it (models.elements.surfaces.ElementSurfaces), or None
    inertia: list[InertiaPoint] = field(default_factory=list)  # its mass, lumped where quadrature puts it


@dataclass
class InertiaPoint:
    """A share of an element's mass: `mass` at the point `position` (2,), and the rotary
    inertia `rotary` of a section turning with the angle `angle` (None: none). The kinetic
    energy is the sum over points of m |dposition/dt|^2 / 2 + J (dangle/dt)^2 / 2."""

    position: ca.SX
    mass: ca.SX
    angle: ca.SX | None = None
    rotary: ca.SX | None = None


class NoEnergyForm(Exception):
    """An element whose model is not the gradient of an energy in the body displacements."""


class NoMassForm(Exception):
    """An element with mass whose unknowns cannot express its kinetic energy."""


@dataclass(frozen=True)
class SiValues:
    """Parameter values in SI, by pointer, for scale hints."""

    values: dict[str, float]
    length_unit_si: float  # one document length unit (section expressions are in it)

    def __getitem__(self, pointer: str) -> float:
        return self.values[pointer]

    def __contains__(self, pointer: str) -> bool:
        return pointer in self.values


@dataclass(frozen=True)
class ScaleHint:
    """Sizes of an element (SI), for nondimensionalizing: a length and a bending stiffness EI
    (beams), or a translational (N/m) or rotational (N m/rad) stiffness (springs)."""

    length: float | None = None
    EI: float | None = None
    stiffness: float | None = None
    rotational_stiffness: float | None = None


@dataclass(frozen=True)
class Discretization:
    """What an element's unknowns cost (service.costs): its statics work (intervals x order^2 of
    shooting, intervals x (degree + 2)^2 of elements), the rotations a contact problem's dense
    KKT matrix grows with, and its number of finite elements (0 for shooting)."""

    work: int
    rotations: int = 0
    elements: int = 0


@dataclass(frozen=True)
class Connector:
    """How the page draws an element that connects two bodies at points (service.drawings.drawing): its
    glyph (the page's vocabulary: "pin" a ring at the point, "slider" a block on its axis,
    "zigzag" a spring between two points); per point the field holding it (global, undeformed)
    and the body whose reference point stands in when the field is left out; a field in the
    document's angle unit to draw (a slider's axis); its kind."""

    glyph: str
    points: tuple[tuple[str, str], ...]
    angle_field: str | None = None
    kind: str | None = None


def beam_discretization(element: Any) -> Discretization:
    """A beam discretized by shooting or by elements (its `discretization`, `intervals`,
    `order` and `degree` fields)."""
    if element.discretization == "elements":
        return Discretization(
            element.intervals * (element.degree + 2) ** 2, element.intervals * element.degree, element.intervals
        )
    return Discretization(element.intervals * element.order**2)


class ElementFamily(Protocol):
    """The contract of an element family. Optional hooks, asked only where a family has them:
    discretization(element, model) -> Discretization | None (what its unknowns cost);
    check_simulated(topology) (raise MechanismError where link dynamics cannot take it);
    model_name(element) -> str (the model a report names); connector(element) -> Connector (the
    page draws it as a connector: pins, sliders, springs); centre_line_sites (attribute: contact
    sites lie on its centre line); invertible (attribute: the link inverse solves its shape);
    kernel_chain and energy_form_counts(topology) (it runs as a chain of element kernels, and
    its own variables and equalities: models.kernels.layout); split_contribution (Cammarata et
    al.'s K_T terms: models.graph.tangent_split); flexure_outputs (a flexures table's columns);
    impact_flexure, impact_constraint, impact_by_statics (models.impacts.families);
    stress_along(P, topology, outputs, points) -> array | None (the outer-fibre stress at each
    deformed centre-line sample of a solved state, nondimensional; P numeric Params, outputs its
    own by short name: models.elements.fibre_stress); fabricated (attribute: "arc" or
    "centre_line", how a fabrication drawing outlines its material: service.drawings.fabrication)."""

    type: str
    schema: builtins.type[TwoBodyElement] | None  # builtins': `type` is the family's name here

    def collect(self, c: Collector, name: str, element: Any, i: int, j: int) -> ElementTopology: ...

    def contribute(self, ctx: AssemblyContext, topology: Any, d: list[ca.SX], z: ca.SX) -> Contribution: ...

    def unknowns(self, topology: Any) -> list[tuple[str, str]]: ...

    def energy_terms(self, ctx: AssemblyContext, topology: Any, d: list[ca.SX]) -> EnergyTerms: ...

    def kinetic_energy(self, ctx: AssemblyContext, topology: Any, d: list[ca.SX], v: list[ca.SX]) -> ca.SX | None: ...

    def scale_hint(self, topology: Any, values: SiValues) -> ScaleHint: ...


class Families:
    """The registered families, by document type and by topology family name."""

    def __init__(self, families: list[ElementFamily]):
        self._by_type: dict[str, ElementFamily] = {}
        self._listeners: list[Callable[[], None]] = []
        for family in families:
            self._add(family)

    def _add(self, family: ElementFamily) -> None:
        if family.type in self._by_type:
            raise ValueError(f"two element families of type '{family.type}'")
        self._by_type[family.type] = family

    def register(self, family: ElementFamily) -> None:
        """Add a family after import (a plug-in, a test): the document schema takes its section
        at once (through the listeners, models.documents.document)."""
        self._add(family)
        self._changed()

    def unregister(self, type_name: str) -> None:
        self._by_type.pop(type_name)
        self._changed()

    def sources(self) -> tuple[str, ...]:
        """The files the families are written in (a registered family's too): what a cache of
        graphs built from them must be keyed by."""
        return tuple(sorted({inspect.getsourcefile(type(family)) or "" for family in self}))

    def on_change(self, listener: Callable[[], None]) -> None:
        """`listener()` runs after every register and unregister."""
        self._listeners.append(listener)

    def _changed(self) -> None:
        for listener in self._listeners:
            listener()

    def __iter__(self) -> Iterator[ElementFamily]:
        return iter(self._by_type.values())

    def named(self, name: str) -> ElementFamily:
        try:
            return self._by_type[name]
        except KeyError:
            raise KeyError(f"unknown element family '{name}' (families: {', '.join(self._by_type)})") from None

    def of(self, topology: ElementTopology) -> ElementFamily:
        return self.named(topology.family)

    def schemas(self) -> tuple[type[TwoBodyElement], ...]:
        """The document sections (a family with no schema of its own is reached through
        another's: a link with discretization 'elements')."""
        return tuple(schema for family in self if (schema := family.schema) is not None)


def constraint_wrenches(
    ctx: AssemblyContext,
    bodies: tuple[int, ...],
    d: list[ca.SX],
    lam: ca.SX,
    constraints: Callable[[list[ca.SX]], ca.SX],
) -> dict[int, ca.SX]:
    """(dg/dd_b)^T lam for the listed bodies: the wrench each applies to a joint whose
    constraints g(d) = 0 have the multipliers lam (the joint's unknowns)."""
    symbols = {b: ca.SX.sym(f"d{b}", 3) for b in bodies}
    local = [symbols.get(b, d[b]) for b in range(ctx.n_bodies)]
    work = ca.dot(lam, constraints(local))
    actual = ca.vertcat(*[d[b] for b in bodies])
    stacked = ca.vertcat(*[symbols[b] for b in bodies])
    return {b: ca.substitute(ca.gradient(work, symbols[b]), stacked, actual) for b in bodies}
