"""The structure of a compiled mechanism: everything that shapes its graphs, and no numbers.

Two documents with the same structure share every CasADi Function; their numbers (positions,
sections, loads, ...) are parameters. The structure's key (a hash of all of it) names the
graphs in memory and on disk.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from functools import cached_property
from typing import Any

COORDINATES = ("x", "y", "angle")


@dataclass(frozen=True)
class Parameter:
    pointer: str
    kind: str  # length | force | moment | stress | angle | ... (models.units.SI_UNITS)
    check: str | None = None  # positive | nonnegative | arc_angle | poisson


@dataclass(frozen=True)
class ElementTopology:
    """The part of an element that shapes the graphs. Each family subclasses it; `family`
    names the family that contributes the element (an exact curved beam is a link)."""

    name: str
    family: str
    start_body: int
    end_body: int

    @property
    def unknowns(self) -> int:
        """How many entries of z the element owns (its own rows match them)."""
        return 0


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
class InertiaTopology:
    """A body with mass: its inertia about the reference point (or none: a point mass) and an
    offset of its mass centre from the reference point (or none)."""

    body: int
    inertia: bool
    center: bool


@dataclass(frozen=True)
class Structure:
    bodies: tuple[str, ...]
    parameters: tuple[Parameter, ...]
    # per body and coordinate: None if free, else the pointer of its prescribed value ("" = 0)
    prescribed: tuple[tuple[str | None, str | None, str | None], ...]
    elements: tuple[ElementTopology, ...]
    loads: tuple[LoadTopology, ...]
    points: tuple[PointTopology, ...]
    reactions: tuple[tuple[str, int], ...]
    masses: tuple[InertiaTopology, ...] = ()
    gravity: bool = False
    length_unit_si: float = 1.0  # SI size of the document's length unit (section expressions use it)
    contacts: Any = None  # models.contact.topology.ContactTopology, or None

    @cached_property
    def key(self) -> str:
        payload = json.dumps(_plain(self), sort_keys=True)
        return hashlib.sha256(payload.encode()).hexdigest()[:16]

    @cached_property
    def without_names(self) -> tuple[Structure, tuple[str, ...]]:
        """(this structure with its names replaced by tokens, the names in token order):
        models.documents.naming."""
        from flexmech.models.documents.naming import anonymous

        return anonymous(self)

    @property
    def unnamed(self) -> Structure:
        """The structure without its names: it keys what every renaming of the structure
        shares (graphs and the solvers built on them)."""
        return self.without_names[0]

    @cached_property
    def free(self) -> tuple[tuple[int, int], ...]:
        return tuple((b, c) for b, row in enumerate(self.prescribed) for c in range(3) if row[c] is None)

    @cached_property
    def element_offsets(self) -> tuple[int, ...]:
        """Where each element's unknowns start in z (after the free body coordinates)."""
        offsets, k = [], len(self.free)
        for element in self.elements:
            offsets.append(k)
            k += element.unknowns
        return tuple(offsets)

    @cached_property
    def n_unknowns(self) -> int:
        return len(self.free) + sum(element.unknowns for element in self.elements)

    @cached_property
    def index(self) -> dict[str, int]:
        return {p.pointer: i for i, p in enumerate(self.parameters)}

    def of_family(self, family: str) -> tuple[ElementTopology, ...]:
        return tuple(element for element in self.elements if element.family == family)

    def coordinate_name(self, body: int, coordinate: int) -> str:
        return f"{self.bodies[body]}.{COORDINATES[coordinate]}"


def _plain(obj: Any) -> Any:
    """JSON-able form of a structure; a dataclass carries its class name, so two topologies
    with the same fields but different meanings hash apart."""
    if hasattr(obj, "__dataclass_fields__"):
        fields = {k: _plain(getattr(obj, k)) for k in obj.__dataclass_fields__}
        return {"__type__": type(obj).__name__, **fields}
    if isinstance(obj, (tuple, list)):
        return [_plain(x) for x in obj]
    return obj
