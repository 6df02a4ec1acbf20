"""Units: document numbers to SI, SI to the document's units, by a small bounded grammar.

A numeric field is a plain number, read in the document's declared unit for its kind, or a
string "<number> <unit>" ("25 um", "300 deg", "1.77 N*m/rad"). The string is read by this
module, not evaluated by pint: a decimal number (at most MAX_NUMBER_CHARS characters), then a
unit made of at most MAX_UNIT_FACTORS unit names joined by * and /, each with an optional
integer power up to MAX_POWER (** or ^), parentheses allowed. pint only looks up single unit
names (their size and dimension; the common ones come from a table of its answers,
unit_names.json, so a process that reads only those neither imports pint nor parses its
definitions); nothing a user writes is run as an expression.

Angles are a dimension of their own here (pint counts the radian as dimensionless): "5 rad"
is not a modulus and "5 percent" not an angle. A unit must have exactly the kind's dimension.
"""

from __future__ import annotations

import json
import re
import sys
from collections import Counter
from functools import cache, lru_cache
from pathlib import Path

from flexmech.models.caches.disk_cache import cache_dir
from flexmech.models.errors import MechanismError


def pint_module():
    """pint, without its optional dask support. Where dask is installed (distributed sweeps)
    pint imports it at once: 0.2 s of every process's start, for dask arrays of quantities that
    flexmech never makes (its quantities are single numbers). importlib's find_spec answers None
    for a name held as None in sys.modules, so pint sees no dask; the entry goes right after."""
    if "dask" in sys.modules or "pint" in sys.modules:
        import pint

        return pint
    sys.modules["dask"] = None  # type: ignore[assignment]
    try:
        import pint
    finally:
        del sys.modules["dask"]
    return pint


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
    "frequency": "Hz",
}

KNOWN_NAMES = Path(__file__).with_name("unit_names.json")
MAX_NUMBER_CHARS = 32
MAX_UNIT_CHARS = 64
MAX_UNIT_FACTORS = 8
MAX_POWER = 4
ANGLE_UNITS = {
    "rad",
    "radian",
    "radians",
    "deg",
    "degree",
    "degrees",
    "arcmin",
    "arcminute",
    "arcsec",
    "arcsecond",
    "turn",
    "revolution",
    "grad",
    "gon",
    "mrad",
    "urad",
}
_NUMBER = re.compile(r"\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d{1,3})?)\s*(.*?)\s*$", re.DOTALL)
_TOKEN = re.compile(r"\s*(\*\*|\^|\*|/|\(|\)|[+-]?\d+|[^\W\d]\w*)")

Dimension = tuple[tuple[str, int], ...]  # sorted (base dimension, power), powers not zero


@lru_cache(maxsize=1)
def registry():
    """pint's registry (pint imported now: 0.2 s a process that reads only common names saves),
    its parsed definitions cached on disk: 30 ms to start, not 150."""
    pint = pint_module()
    try:
        return pint.UnitRegistry(cache_folder=cache_dir() / "pint")
    except OSError:  # a read-only cache folder: parse the definitions every time
        return pint.UnitRegistry()


def _shown(text: str, limit: int = 40) -> str:
    """A user's text in a message: quoted, and cut when long (never echoed whole)."""
    return repr(text) if len(text) <= limit else repr(text[:limit]) + f"... ({len(text)} characters)"


@lru_cache(maxsize=1)
def _known() -> dict[str, tuple[float, Dimension]]:
    """pint's answers for the unit names documents use most (scripts/unit_names.py writes them,
    tests/documents/test_unit_names.py checks them): a process on an empty cache reads these instead of
    parsing pint's definitions, 0.5-0.75 s."""
    try:
        table = json.loads(KNOWN_NAMES.read_text())
    except (OSError, ValueError):
        return {}
    return {
        name: (float(size), tuple((str(d), int(p)) for d, p in dimension)) for name, (size, dimension) in table.items()
    }


@lru_cache(maxsize=512)
def _named(name: str) -> tuple[float, Dimension]:
    """SI size and dimension of one unit name: from the table of common names, else pint's."""
    known = _known().get(name)
    return known if known is not None else pint_named(name)


def pint_named(name: str) -> tuple[float, Dimension]:
    """SI size and dimension of one unit name as pint has it (pint looks the name up; nothing
    is evaluated)."""
    ureg = registry()
    if name in ANGLE_UNITS:
        return float(ureg.Quantity(1.0, name).to("rad").magnitude), (("[angle]", 1),)
    try:
        quantity = ureg.Quantity(1.0, ureg.Unit(name)).to_base_units()
    except (pint_module().errors.PintError, AttributeError, ValueError, TypeError):
        raise ValueError(f"unknown unit '{name}'") from None
    dimension = tuple(sorted((str(d), int(p)) for d, p in quantity.dimensionality.items() if p))
    return float(quantity.magnitude), dimension


class _UnitParser:
    """unit := factor (('*' | '/') factor)*;  factor := (name | '(' unit ')') [('**' | '^') int]"""

    def __init__(self, text: str):
        self.tokens, position = [], 0
        while position < len(text):
            match = _TOKEN.match(text, position)
            if match is None:
                if text[position:].strip():
                    raise ValueError(f"cannot read {_shown(text[position:], 12)}")
                break
            self.tokens.append(match.group(1))
            position = match.end()
        self.at, self.factors = 0, 0

    def peek(self) -> str | None:
        return self.tokens[self.at] if self.at < len(self.tokens) else None

    def take(self) -> str:
        token = self.peek()
        if token is None:
            raise ValueError("the unit ends too soon")
        self.at += 1
        return token

    def unit(self) -> tuple[float, Counter]:
        size, dims = self.factor()
        while self.peek() in ("*", "/"):
            divide = self.take() == "/"
            f, d = self.factor()
            size = size / f if divide else size * f
            dims.update({k: -v if divide else v for k, v in d.items()})
        return size, dims

    def factor(self) -> tuple[float, Counter]:
        self.factors += 1
        if self.factors > MAX_UNIT_FACTORS:
            raise ValueError(f"more than {MAX_UNIT_FACTORS} unit factors")
        token = self.take()
        if token == "(":
            size, dims = self.unit()
            if self.take() != ")":
                raise ValueError("a parenthesis is not closed")
        elif token[0].isalpha() or token[0] == "_":
            size, dimension = _named(token)
            dims = Counter(dict(dimension))
        else:
            raise ValueError(f"expected a unit name, got '{token}'")
        if self.peek() in ("**", "^"):
            self.take()
            power = self.take()
            if not re.fullmatch(r"[+-]?\d+", power) or abs(int(power)) > MAX_POWER:
                raise ValueError(f"powers of units are integers up to {MAX_POWER}, got '{power}'")
            size, dims = size ** int(power), Counter({k: v * int(power) for k, v in dims.items()})
        return size, dims


@lru_cache(maxsize=1024)
def parse_unit(text: str) -> tuple[float, Dimension]:
    """(SI size, dimension) of a unit text; ValueError saying what is wrong."""
    if not isinstance(text, str) or not text.strip():
        raise ValueError("expected a unit")
    if len(text) > MAX_UNIT_CHARS:
        raise ValueError(f"a unit is at most {MAX_UNIT_CHARS} characters")
    if text.strip() == "dimensionless":
        return 1.0, ()
    parser = _UnitParser(text)
    size, dims = parser.unit()
    if parser.peek() is not None:
        raise ValueError(f"unexpected '{parser.peek()}' (join units with * or /)")
    return size, tuple(sorted((k, v) for k, v in dims.items() if v))


@cache
def dimension_of(kind: str) -> Dimension:
    return parse_unit(SI_UNITS[kind] or "dimensionless")[1]


@lru_cache(maxsize=512)
def unit_factor(unit: str, kind: str, pointer: str) -> float:
    """SI value of one `unit` of quantity `kind`; MechanismError(pointer) on a bad unit."""
    try:
        size, dimension = parse_unit(unit)
    except ValueError as exc:
        raise MechanismError(pointer, f"{_shown(str(unit))} is not a unit of {kind}: {exc}") from None
    if dimension != dimension_of(kind):
        raise MechanismError(pointer, f"{_shown(unit)} is not a unit of {kind} (like {SI_UNITS[kind] or '1'})")
    return size


def quantity_to_si(value: float | int | str, kind: str, default_unit: str, pointer: str) -> float:
    """Convert a document number (bare: in `default_unit`; string: with its own unit) to SI."""
    if isinstance(value, bool):
        raise MechanismError(pointer, f"expected a number or a quantity string, got {value!r}")
    if isinstance(value, (int, float)):
        return float(value) * unit_factor(default_unit, kind, pointer)
    if isinstance(value, str):
        return _string_to_si(value, kind, default_unit, pointer)
    raise MechanismError(pointer, f"expected a number or a quantity string, got {_shown(repr(value))}")


@lru_cache(maxsize=4096)
def _string_to_si(value: str, kind: str, default_unit: str, pointer: str) -> float:
    """A quantity string "<number> [unit]" in SI (without a unit: the document's unit)."""
    match = _NUMBER.match(value) if len(value) <= MAX_NUMBER_CHARS + MAX_UNIT_CHARS + 2 else None
    if match is None or len(match.group(1)) > MAX_NUMBER_CHARS:
        raise MechanismError(
            pointer,
            f"cannot read {_shown(value)} as a quantity: expected a number "
            f"(at most {MAX_NUMBER_CHARS} characters) and a unit, like '25 um'",
        )
    number, unit = float(match.group(1)), match.group(2)
    if not unit:
        return number * unit_factor(default_unit, kind, pointer)
    try:
        size, dimension = parse_unit(unit)
    except ValueError as exc:
        raise MechanismError(pointer, f"cannot read {_shown(value)} as a quantity: {exc}") from None
    if dimension != dimension_of(kind):
        article = "an" if kind[:1] in "aeiou" else "a"  # "is not an angle"
        raise MechanismError(pointer, f"{_shown(value)} is not {article} {kind} (expected units like {default_unit})")
    return number * size


_DOCUMENT_UNITS = {  # kind -> its unit, as text, from a document's declared units
    "length": lambda u: u.length,
    "force": lambda u: u.force,
    "moment": lambda u: f"{u.force}*{u.length}",
    "energy": lambda u: f"{u.force}*{u.length}",
    "stress": lambda u: u.stress,
    "angle": lambda u: u.angle,
    "stiffness": lambda u: f"{u.force}/{u.length}",
    "area": lambda u: f"({u.length})**2",
    "second_moment": lambda u: f"({u.length})**4",
    "dimensionless": lambda u: "dimensionless",
    "mass": lambda u: u.mass,
    "inertia": lambda u: f"{u.mass}*({u.length})**2",
    "density": lambda u: f"{u.mass}/({u.length})**3",
    "acceleration": lambda u: f"{u.length}/s**2",
    "rotational_stiffness": lambda u: f"{u.force}*{u.length}/{u.angle}",
    "frequency": lambda u: "Hz",  # time is in seconds in every document
}


def document_unit(units, kind: str) -> str:
    """The unit, as text, in which a document with `units` (models.documents.document.Units) states a
    quantity of `kind`; derived kinds are products of the declared ones. (Called for every
    output of every report: only the kind asked for is made.)"""
    return _DOCUMENT_UNITS[kind](units)
