"""How a result's numbers are shown: one module for the command line, the page and the plots
(JSON and CSV keep the exact values in the document's units).

A quantity is shown in a display unit: the document's own while the largest magnitude shown
lies in [0.1, 1e4) (KEPT; not for stresses and energies, ALWAYS_PREFIXED), else the document's unit with the SI prefix of its first factor
chosen so that it lies in [1, 1000) (0.00147 GPa -> 1.47 MPa, 1.2e-9 kg -> 1.2 ug); an energy
in J with its prefix (4.77 uN*mm -> 4.77 nJ). Every number has SIGNIFICANT digits, and a
value below the noise floor of its quantity, NOISE times the largest of its kind in the same
result (a few times the solver's relative accuracy: its residual tolerance is 1e-10 of the
largest force it balances), is shown as 0: round-off such as an output of -6.9e-15 mm where the others are
millimetres is not a result. Residuals and tolerances are not results: they are shown exactly
(exact()).

    shown = display("GPa", [0.00146703, 0.00121])
    shown.unit, shown.text(0.00146703)        # ('MPa', '1.46703')
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass

from flexmech.models.units import parse_unit

SIGNIFICANT = 6
NOISE = 1e-9  # a few times the solver's tolerance: its round-off reaches 2e-10 of the largest
KEPT = (0.1, 1e4)  # the document's unit is kept while the largest value shown lies in this range
# ... except for these, which engineers always write with the prefix that puts them in [1, 1000)
# (a stress of 0.189 GPa is 189 MPa; a document's stress unit is its modulus', not a choice)
ALWAYS_PREFIXED = ("Pa", "J")
PREFIXES = ("p", "n", "u", "m", "", "k", "M", "G")
# units whose first factor takes an SI prefix (a degree, a percent or a turn does not)
PREFIXED = ("m", "g", "N", "Pa", "J", "Hz", "s", "W")  # not rad: krad/s is no engineer's unit
_FIRST = re.compile(r"^([A-Za-zµ]+)(.*)$")


@dataclass(frozen=True)
class Display:
    """How one quantity's values are shown: in `unit`, each value (in the original unit) times
    `factor`, those of magnitude below `floor` (original unit) as 0."""

    unit: str
    factor: float = 1.0
    floor: float = 0.0

    def value(self, value: float | None) -> float | None:
        """The value as shown (None stays None), round-off below the floor 0."""
        if value is None or not math.isfinite(value):
            return None
        return 0.0 if abs(value) < self.floor else value * self.factor

    def text(self, value: float | None, with_unit: bool = False) -> str:
        shown = self.value(value)
        text = "-" if shown is None else number_text(shown)
        return f"{text} {self.unit}" if with_unit and self.unit else text


def number_text(value: float) -> str:
    """SIGNIFICANT digits, trailing zeros dropped; -0 is 0."""
    if value == 0:
        return "0"
    return f"{value:.{SIGNIFICANT}g}"


def exact(value: float | None, unit: str = "") -> str:
    """A residual or a tolerance: its own value (no floor), four digits, and its unit."""
    text = "-" if value is None else f"{value:.4g}"
    return f"{text} {unit}".strip()


def _split(unit: str) -> tuple[str, str, str] | None:
    """(prefix, base symbol, rest) of a unit whose first factor takes an SI prefix."""
    found = _FIRST.match(unit.strip())
    if found is None:
        return None
    first, rest = found.groups()
    first = first.replace("µ", "u")
    if first in PREFIXED:
        return "", first, rest
    if len(first) > 1 and first[0] in PREFIXES and first[1:] in PREFIXED:
        return first[0], first[1:], rest
    return None


def _factor(unit: str, to: str) -> float:
    """What one `unit` is in `to` (same dimension)."""
    return parse_unit(unit)[0] / parse_unit(to)[0]


def display(unit: str, values: Iterable[float | None], kind: str | None = None, reference: float = 0.0) -> Display:
    """The display of a quantity in `unit` (the document's) whose values in one result are
    `values`; `kind` "energy" shows it in J, "ratio" (a multiplier, a gain) keeps its unit.
    `reference`: the quantity's scale in the model (one nondimensional unit, to which the
    solver's tolerance applies), below NOISE times which a value is round-off even when it is
    the largest shown (a constraint held at 0 ends at 5e-19 mm)."""
    finite = [abs(v) for v in values if v is not None and math.isfinite(v)]
    floor = NOISE * max(max(finite, default=0.0), reference)
    largest = max((v for v in finite if v >= floor), default=0.0)
    if kind == "ratio":
        return Display(unit, 1.0, floor)
    base_unit = "J" if kind == "energy" and unit else unit
    split = _split(base_unit)
    always = split is not None and split[1] in ALWAYS_PREFIXED
    if base_unit == unit and KEPT[0] <= largest < KEPT[1] and not always:
        return Display(unit, 1.0, floor)
    if split is None or largest == 0:
        if base_unit != unit:
            return Display(base_unit, _factor(unit, base_unit), floor)
        return Display(unit, 1.0, floor)
    _, base, rest = split
    best = None
    for prefix in PREFIXES:
        candidate = f"{prefix}{base}{rest}"
        try:
            factor = _factor(unit, candidate)
        except ValueError:
            continue
        shown = largest * factor
        score = 0 if 1 <= shown < 1000 else min(abs(math.log10(shown)), abs(math.log10(shown / 1000)))
        if best is None or score < best[0]:
            best = (score, candidate, factor)
    _, candidate, factor = best
    if candidate == unit:
        factor = 1.0  # exactly the document's values
    return Display(candidate, factor, floor)


def displays(
    values: dict[str, float | None], units: dict[str, str], kinds: dict[str, str] | None = None
) -> dict[str, Display]:
    """A display per name, one per quantity: the names sharing a unit (and kind) share its
    display, chosen from all their values."""
    kinds = kinds or {}
    groups: dict[tuple[str, str], list[float | None]] = {}
    for name, value in values.items():
        groups.setdefault((units.get(name, ""), kinds.get(name, "")), []).append(value)
    chosen = {key: display(key[0], group, key[1] or None) for key, group in groups.items()}
    return {name: chosen[(units.get(name, ""), kinds.get(name, ""))] for name in values}


def on_axis(unit: str, arrays, kind: str | None = None) -> tuple[str, list]:
    """(display unit, the arrays in it) of one plotted quantity: a figure's axis reads as the
    tables do (0.19 GPa stresses on an MPa axis). NaN (a point left out) stays NaN."""
    import numpy as np

    arrays = [np.asarray(a, dtype=float) for a in arrays]
    values = [float(v) for a in arrays for v in a.ravel() if np.isfinite(v)]
    shown = display(unit, values, kind)
    return shown.unit, [np.where(np.abs(a) < shown.floor, 0.0, a * shown.factor) for a in arrays]
