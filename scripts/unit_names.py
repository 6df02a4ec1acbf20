"""Writes models/unit_names.json: pint's answer (SI size, dimension) for the unit names documents
use most, so that a process on an empty cache reads them instead of parsing pint's definitions
(0.5-0.75 s). models.units reads the table first and asks pint for any other name;
tests/documents/test_unit_names.py checks that every entry is still pint's answer. Run from the repository
root after upgrading pint or adding names:

    python3 scripts/unit_names.py
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

PREFIXED = {
    "m": ("n", "u", "m", "c", "k", ""),
    "N": ("n", "u", "m", "k", "M", ""),
    "Pa": ("k", "M", "G", ""),
    "g": ("u", "m", "k", ""),
    "s": ("u", "m", ""),
    "J": ("u", "m", "k", ""),
    "W": ("m", "k", ""),
}
OTHERS = (
    "rad",
    "mrad",
    "urad",
    "deg",
    "degree",
    "degrees",
    "radian",
    "radians",
    "arcmin",
    "arcsec",
    "turn",
    "inch",
    "ft",
    "lbf",
    "psi",
    "percent",
    "Hz",
    "kHz",
    "min",
    "h",
)
TABLE = Path(__file__).resolve().parents[1] / "models" / "unit_names.json"


def names() -> list[str]:
    out = [prefix + base for base, prefixes in PREFIXED.items() for prefix in prefixes]
    return out + [name for name in OTHERS if name not in out]


def main() -> None:
    sys.path.insert(0, str(TABLE.parents[1]))  # this checkout's models, installed or not
    from flexmech.models import units

    table = {}
    for name in names():
        size, dimension = units.pint_named(name)
        table[name] = [size, [list(item) for item in dimension]]
    lines = [f"  {json.dumps(name)}: {json.dumps(table[name])}" for name in sorted(table)]
    TABLE.write_text("{\n" + ",\n".join(lines) + "\n}\n")
    print(f"{len(table)} unit names written to {TABLE}")


if __name__ == "__main__":
    main()
