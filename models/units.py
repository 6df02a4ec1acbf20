"""Unit handling with pint: document numbers to SI, SI to the document's units.

A numeric field is either a plain number, read in the document's declared unit for that
quantity, or a string with its own unit ("25 um", "300 deg"). Internally everything is SI.
"""

from __future__ import annotations

from functools import lru_cache

import pint

from models.errors import MechanismError
from models.graph_cache import cache_dir

# The kinds of quantity a document holds, with the SI unit each converts to.
SI_UNITS: dict[str, str] = {
    "length": "m",
    "force": "N",
    "moment": "N*m",
    "stress": "Pa",
    "angle": "rad",
    "mass": "kg",
    "inertia": "kg*m**2",
    "energy": "J",
    "stiffness": "N/m",
    "dimensionless": "",
    "area": "m**2",
    "second_moment": "m**4",
    "density": "kg/m**3",
    "acceleration": "m/s**2",
    "rotational_stiffness": "N*m/rad",
}


@lru_cache(maxsize=1)
def registry() -> pint.UnitRegistry:
    """pint's registry, its parsed definitions cached on disk: 30 ms to start, not 150."""
    try:
        return pint.UnitRegistry(cache_folder=cache_dir() / "pint")
    except OSError:  # a read-only cache folder: parse the definitions every time
        return pint.UnitRegistry()


@lru_cache(maxsize=512)
def unit_factor(unit: str, kind: str, pointer: str) -> float:
    """SI value of one `unit` of quantity `kind`; raises MechanismError on a bad unit."""
    ureg = registry()
    try:
        quantity = ureg.Quantity(1.0, unit)
        return float(quantity.to(SI_UNITS[kind]).magnitude)
    except (pint.errors.UndefinedUnitError, pint.errors.DimensionalityError, AttributeError,
            ValueError, TypeError) as exc:
        raise MechanismError(pointer, f"'{unit}' is not a unit of {kind} ({exc})") from None


def quantity_to_si(value: float | int | str, kind: str, default_unit: str, pointer: str) -> float:
    """Convert a document number (bare: in `default_unit`; string: with its own unit) to SI."""
    if isinstance(value, bool):
        raise MechanismError(pointer, f"expected a number or a quantity string, got {value!r}")
    if isinstance(value, (int, float)):
        return float(value) * unit_factor(default_unit, kind, pointer)
    if isinstance(value, str):
        return _string_to_si(value, kind, default_unit, pointer)
    raise MechanismError(pointer, f"expected a number or a quantity string, got {value!r}")


@lru_cache(maxsize=4096)
def _string_to_si(value: str, kind: str, default_unit: str, pointer: str) -> float:
    """A quantity string in SI. Cached: pint's parser takes about half a millisecond, and the
    same strings ("25 um") come back with every request for a document."""
    ureg = registry()
    try:
        quantity = ureg.Quantity(value)
    except Exception as exc:  # pint raises many parser-level types for free text
        raise MechanismError(pointer, f"cannot read {value!r} as a quantity ({exc})") from None
    if isinstance(quantity, (int, float)) or quantity.dimensionless:
        magnitude = float(quantity.magnitude if hasattr(quantity, "magnitude") else quantity)
        if kind == "angle" and hasattr(quantity, "units") and str(quantity.units) != "dimensionless":
            return float(quantity.to("rad").magnitude)
        return magnitude * unit_factor(default_unit, kind, pointer)
    try:
        return float(quantity.to(SI_UNITS[kind]).magnitude)
    except pint.errors.DimensionalityError:
        raise MechanismError(
            pointer, f"{value!r} is not a {kind} (expected units like {default_unit})"
        ) from None


def document_unit(units, kind: str) -> str:
    """The unit, as pint text, in which a document with `units` (models.document.Units)
    states a quantity of `kind`; derived kinds are products of the declared ones."""
    return {
        "length": units.length,
        "force": units.force,
        "moment": f"{units.force}*{units.length}",
        "energy": f"{units.force}*{units.length}",
        "stress": units.stress,
        "angle": units.angle,
        "stiffness": f"{units.force}/{units.length}",
        "area": f"({units.length})**2",
        "second_moment": f"({units.length})**4",
        "dimensionless": "dimensionless",
        "mass": units.mass,
        "inertia": f"{units.mass}*({units.length})**2",
        "density": f"{units.mass}/({units.length})**3",
        "acceleration": f"{units.length}/s**2",
        "rotational_stiffness": f"{units.force}*{units.length}/{units.angle}",
    }[kind]
