"""A compiled mechanism: its structure, parameter values and graphs.

The structure (bodies, which coordinates are free, element topologies and models, where loads
and outputs sit) decides the graphs; every number of the document is a parameter. Graphs are
built once per structure and cached by its hash, so changing a load, a section or a radius
never rebuilds anything. Parameters are passed nondimensionalized: lengths by the largest
element size (flexure radius, link length), forces by the largest EI over that length
squared, so a case in (uN, mm) and its SI copy present the same numbers to the solver.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from flexmech.models.documents.document import MechanismDocument
from flexmech.models.elements import FAMILIES
from flexmech.models.elements.base import SiValues
from flexmech.models.errors import MechanismError
from flexmech.models.graph.collect import collect
from flexmech.models.graph.collector import check_value
from flexmech.models.graph.structure import COORDINATES, Parameter, Structure
from flexmech.models.units import document_unit, quantity_to_si, unit_factor

__all__ = ["COORDINATES", "Mechanism", "Scales", "compile_mechanism"]


@dataclass(frozen=True)
class Scales:
    """SI size of one nondimensional unit of each kind of quantity. Time is in seconds, so a
    mass unit is force / length and accelerations are lengths per second squared."""

    length: float
    force: float

    def of(self, kind: str) -> float:
        return self._table[kind]

    @cached_property
    def _table(self) -> dict[str, float]:
        L, F = self.length, self.force
        return {
            "length": L,
            "force": F,
            "moment": F * L,
            "energy": F * L,
            "stress": F / L**2,
            "angle": 1.0,
            "stiffness": F / L,
            "rotational_stiffness": F * L,
            "area": L**2,
            "second_moment": L**4,
            "dimensionless": 1.0,
            "mass": F / L,
            "inertia": F * L,
            "acceleration": L,
            "density": F / L**4,
            "frequency": 1.0,
        }


def _scales(structure: Structure, si: np.ndarray) -> Scales:
    values = SiValues({p.pointer: v for p, v in zip(structure.parameters, si)}, structure.length_unit_si)
    hints = [FAMILIES.of(t).scale_hint(t, values) for t in structure.elements]
    beams = [(h.length, h.EI) for h in hints if h.length is not None and h.EI is not None]
    if beams:
        length = max(size for size, _ in beams)
        return Scales(length=length, force=max(EI for _, EI in beams) / length**2)
    positions = [abs(v) for p, v in zip(structure.parameters, si) if p.kind == "length"]
    length = max([x for x in positions if x > 0], default=1.0)
    forces = [h.stiffness * length for h in hints if h.stiffness]
    forces += [h.rotational_stiffness / length for h in hints if h.rotational_stiffness]
    return Scales(length=length, force=max(forces, default=1.0))


@dataclass(frozen=True)
class Mechanism:
    """A compiled mechanism: its structure, parameter values (SI) and graphs.

    Unknowns z are the displacements of the free body coordinates from the undeformed pose
    (nondimensional: lengths / scales.length, angles in rad), in `structure.free` order, then
    every element's own unknowns.
    """

    document: MechanismDocument
    structure: Structure
    si_values: np.ndarray
    scales: Scales
    notes: tuple[str, ...] = field(default=())  # inputs its models do not use

    @property
    def parameters(self) -> tuple[Parameter, ...]:
        return self.structure.parameters

    @property
    def free_coordinates(self) -> list[str]:
        return [self.structure.coordinate_name(b, c) for b, c in self.structure.free]

    @property
    def n_free(self) -> int:
        """Number of unknowns z: free body coordinates, then the elements' own unknowns."""
        return self.structure.n_unknowns

    @property
    def n_body_coordinates(self) -> int:
        return len(self.structure.free)

    @cached_property
    def graphs(self):
        from flexmech.models.graph.assembly import graphs_for

        return graphs_for(self.structure)

    # --- units -------------------------------------------------------------------------
    def doc_unit(self, kind: str) -> str:
        return document_unit(self.document.units, kind)

    def doc_factor(self, kind: str) -> float:
        """SI value of one document unit of `kind`."""
        return unit_factor(self.doc_unit(kind), kind, kind)

    def nd_per_doc(self, kind: str) -> float:
        """Nondimensional value of one document unit of `kind`."""
        found = self._nd_per_doc.get(kind)
        if found is None:
            found = self._nd_per_doc[kind] = self.doc_factor(kind) / self.scales.of(kind)
        return found

    @cached_property
    def _nd_per_doc(self) -> dict[str, float]:
        return {}  # by kind, filled as asked (a report asks dozens of times)

    # --- parameters ----------------------------------------------------------------------
    def parameter_index(self, pointer: str) -> int:
        try:
            return self.structure.index[pointer]
        except KeyError:
            close = [p.pointer for p in self.parameters if p.pointer.startswith(pointer.rsplit("/", 1)[0])]
            hint = f" (numeric fields here: {', '.join(close[:8])})" if close else ""
            raise MechanismError(pointer, f"not a numeric field of this mechanism{hint}") from None

    def parameter_indices(self, paths: list[str], pointer: str) -> list[int]:
        """parameter_index of each path, a problem named at `pointer`/k (the k-th path)."""
        slots = []
        for k, path in enumerate(paths):
            try:
                slots.append(self.parameter_index(path))
            except MechanismError as exc:
                raise MechanismError(f"{pointer}/{k}", f"'{path}' is {exc.problem}") from None
        return slots

    def parameter_kind(self, pointer: str) -> str:
        return self.parameters[self.parameter_index(pointer)].kind

    def p(self) -> np.ndarray:
        """Nondimensional parameter vector (a copy: the caller may change it)."""
        return self._p.copy()

    @cached_property
    def _p(self) -> np.ndarray:
        kinds = np.array([self.scales.of(p.kind) for p in self.parameters])
        return self.si_values / kinds

    def checked_si(self, path: str, value: float | str, pointer: str | None = None, own_checks: bool = True) -> float:
        """A value of the numeric field `path` (document units, or a quantity string) in SI,
        checked like the document's own (magnitude; with own_checks, the field's sign or
        range too); errors name `pointer` (default: path)."""
        param = self.parameters[self.parameter_index(path)]
        unit = self.doc_unit(param.kind)
        where = path if pointer is None else pointer
        si = quantity_to_si(value, param.kind, unit, where)
        check_value(where, si, param.check if own_checks else None, unit, self.doc_factor(param.kind), value)
        return si

    def with_values(self, overrides: dict[str, float | str]) -> Mechanism:
        """A copy with numeric fields replaced; values in document units (or quantity strings)."""
        si = self.si_values.copy()
        for pointer, value in overrides.items():
            si[self.parameter_index(pointer)] = self.checked_si(pointer, value)
        return replace(self, si_values=si)

    def value(self, pointer: str) -> float:
        """Current value of a numeric field, in document units."""
        i = self.parameter_index(pointer)
        return float(self.si_values[i] / self.doc_factor(self.parameters[i].kind))


def compile_mechanism(document: MechanismDocument, model: str | None = None, grounded: bool = True) -> Mechanism:
    """Check a validated document and prepare its graphs (built lazily, cached by structure).

    `model` overrides the model of every curved beam (models.MODELS); `grounded` False skips
    the check that every body reaches a fixed one (models.graph.collect.collect).
    """
    structure, si, notes = collect(document, model, grounded)
    return Mechanism(
        document=document, structure=structure, si_values=si, scales=_scales(structure, si), notes=tuple(notes)
    )
