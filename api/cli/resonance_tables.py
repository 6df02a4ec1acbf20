"""The resonances of a frequency response as tables whose heads carry their units: frequency
and bandwidth in Hz, phase in degrees, the amplitude in the output's unit per the input's (one
table per such unit, when the outputs differ in it)."""

from __future__ import annotations

from rich.table import Table

from flexmech.api.cli.record_tables import records_table

UNITS = {"frequency": "Hz", "bandwidth": "Hz", "phase": "deg"}


def resonance_tables(report: dict) -> list[Table]:
    """A table of the report's resonances per amplitude unit (the outputs' units per the
    input's, from its responses), every row of the report in one of them."""
    responses = report.get("responses") or {}
    groups: dict[str, list[dict]] = {}
    for row in report["resonances"]:
        unit = (responses.get(row.get("output")) or {}).get("unit") or ""
        groups.setdefault(unit, []).append(row)
    tables = []
    for unit, rows in groups.items():
        units = {**UNITS, "amplitude": unit} if unit else dict(UNITS)
        title = "resonances" if len(groups) == 1 else f"resonances of the outputs in {unit or 'no unit'}"
        tables.append(records_table(title, rows, units))
    return tables
