"""The collector: what an element family reads its document section through. Numbers become
parameters (checked, in SI); references to bodies, materials and sections are checked and
recorded, so materials and sections are collected once, for what their users need."""

from __future__ import annotations

import math
from typing import Any

from flexmech.models.errors import MechanismError
from flexmech.models.graph.structure import Parameter
from flexmech.models.units import document_unit, quantity_to_si, unit_factor

# Numbers of any kind, in SI, lie within these magnitudes (or are zero): beyond them a
# document holds a typo, and the solver's nondimensional numbers would overflow or vanish.
LARGEST, SMALLEST = 1e30, 1e-30


def _in_range(value: float) -> bool:
    return value == 0 or SMALLEST <= abs(value) <= LARGEST


def check_value(
    pointer: str, si: float, check: str | None, unit: str = "", factor: float = 1.0, given: object = None
) -> None:
    """A numeric field's physical range. `si` in SI; `unit` and `factor` (SI per unit) say how
    the document states it, for the message; `given` is the number as written, when it was one."""
    shown = f"{si:g} (SI)" if factor == 1.0 or not unit else f"{si / factor:g} {unit}"
    if isinstance(given, (int, float)) and not isinstance(given, bool):
        shown = f"{given:g}" + (f" {unit}" if unit and factor != 1.0 else " (SI)" if factor == 1.0 and unit else "")
        if not math.isfinite(given) or not _in_range(float(given)):
            si = float("inf")
    if not math.isfinite(si) or not _in_range(si):
        raise MechanismError(
            pointer, f"{shown} is out of range: magnitudes from {SMALLEST:g} to {LARGEST:g} in SI units (or zero)"
        )
    if check == "positive" and si <= 0:
        raise MechanismError(pointer, f"must be positive, got {shown}")
    if check == "nonnegative" and si < 0:
        raise MechanismError(pointer, f"must not be negative, got {shown}")
    if check == "poisson" and not (-1.0 < si <= 0.5):
        raise MechanismError(pointer, f"Poisson's ratio must lie in (-1, 0.5], got {si:g}")
    if check == "arc_angle" and not (0.0 < si < 2 * math.pi):
        deg = math.degrees(si)
        raise MechanismError(pointer, f"arc angle must lie in (0, 360) deg, got {deg:g} deg")


class Collector:
    """What a family reads a document section through: numbers become parameters (checked,
    in SI), references to bodies, materials and sections are checked and recorded."""

    def __init__(self, doc: Any, model_override: str | None):  # doc: a models.documents.document.MechanismDocument
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
        unit = self.unit_of(kind)
        si = quantity_to_si(value, kind, unit, pointer)
        check_value(pointer, si, check, unit, unit_factor(unit, kind, pointer), value)
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
            raise MechanismError(
                pointer, f"unknown material '{name}' (materials: {', '.join(self.doc.materials) or 'none'})"
            )
        needs = self.materials.setdefault(name, {"shear": False, "density": False})
        needs["shear"] |= shear

    def use_section(self, name: str, pointer: str, needs_area: bool = False):
        if name not in self.doc.sections:
            raise MechanismError(
                pointer, f"unknown section '{name}' (sections: {', '.join(self.doc.sections) or 'none'})"
            )
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
