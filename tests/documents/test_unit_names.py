"""The table of common unit names (models/unit_names.json, written by scripts/unit_names.py)
holds pint's own answers, so a process that reads it instead of parsing pint's definitions
converts every number exactly as pint would."""

from __future__ import annotations

import json

from flexmech.models import units


def test_every_name_in_the_table_is_pints_answer_to_the_last_bit():
    table = json.loads(units.KNOWN_NAMES.read_text())
    assert {"m", "mm", "um", "N", "uN", "Pa", "GPa", "rad", "deg", "kg", "s"} <= set(table)
    for name, (size, dimension) in table.items():
        assert (size, tuple(tuple(d) for d in dimension)) == units.pint_named(name), name


def test_a_name_outside_the_table_is_asked_of_pint():
    units._named.cache_clear()
    assert "mile" not in units._known()
    size, dimension = units._named("mile")
    assert abs(size - 1609.344) < 1e-9 and dimension == (("[length]", 1),)
    assert units.unit_factor("N*m/rad", "rotational_stiffness", "/x") == 1.0
