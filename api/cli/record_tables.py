"""A report's list of records (the modes of a modes report, one row each) as a table: a column
per field that is a number or a word, and per entry of a field that is a mapping with the same
names in every row (effective_mass: x, y); mappings that differ from row to row (a mode's
energy shares) stay in --json. A column's unit comes from the report's `units` by field name."""

from __future__ import annotations

from typing import Any

from rich.table import Table

from flexmech.api.cli.common import shown, table_of


def _scalar(value: Any) -> bool:
    return value is None or isinstance(value, (int, float, str)) and not isinstance(value, bool)


def is_records(value: Any) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(row, dict) for row in value)


def _columns(rows: list[dict]) -> list[tuple[str, str | None]]:
    """(field, entry or None) of every column the rows share."""
    columns: list[tuple[str, str | None]] = []
    for key, value in rows[0].items():
        if all(_scalar(row.get(key)) for row in rows):
            columns.append((key, None))
        elif isinstance(value, dict) and all(
            isinstance(row.get(key), dict) and list(row[key]) == list(value) for row in rows
        ):
            if all(_scalar(v) for row in rows for v in row[key].values()):
                columns += [(key, entry) for entry in value]
    return columns


# Fields a table leaves to --json: omega and its square say what the frequency in Hz says, in
# magnitudes (3.6e5 rad/s, 1.3e11 rad^2/s^2) no engineer reads.
LEFT_TO_JSON = ("omega", "omega_squared")


def records_table(title: str, rows: list[dict], units: dict[str, str]) -> Table:
    columns = [c for c in _columns(rows) if c[0] not in LEFT_TO_JSON or "frequency" not in rows[0]]
    heads = []
    for key, entry in columns:
        unit = units.get(key)
        head = key if entry is None else f"{key} {entry}"
        heads.append(f"{head} ({unit})" if unit else head)
    table = table_of(title, *heads, text=1 if isinstance(rows[0].get(columns[0][0]), str) else 0)
    for row in rows:
        cells = []
        for key, entry in columns:
            value = row.get(key) if entry is None else row[key].get(entry)
            cells.append(shown(value) if isinstance(value, str) else value)
        table.add_row(*cells)
    return table
