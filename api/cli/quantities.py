"""Numbers as the command line shows them (service.display's rules): a table's numeric columns
get their display unit when the table is printed, from every value the table holds, so that a
column of stresses in GPa prints in MPa, masses in kg print in ug, energies in J, and round-off
beside real values prints as 0. A column's unit is the one its head ends with, "x [mm]" or
"mass (kg)"; a table whose units vary by row names its unit column (unit_column). Residual and
tolerance columns are shown exactly; matrices, whose cells each have their own unit, are
formatted by their printer and passed as text."""

from __future__ import annotations

import re
import unicodedata
from typing import Any

from rich.markup import escape
from rich.table import Table

_HEAD_UNIT = re.compile(r"^(?P<name>.*?)\s*(?P<open>[\[(])(?P<unit>[^\[\]()]*)[\])]$")
_NOT_RESULTS = ("residual", "tolerance")
# A table of named outputs, each in its document unit: below NOISE x this many units (1e-12 of a
# mm, a uN, a degree) a value is round-off even when all of its unit are (an unloaded contact
# state's forces of 7e-14 uN). Masses and other SI quantities are not in these tables.
ONE_UNIT_REFERENCE = 1e-3


def head_unit(head: str) -> tuple[str, str, str]:
    """(name, unit, bracket) of a column head "name [unit]" or "name (unit)"; unit "" if none."""
    found = _HEAD_UNIT.match(head)
    if found is None:
        return head, "", "["
    return found["name"], found["unit"].strip(), found["open"]


def kind_of(head: str) -> str | None:
    """'energy' for an energy column (shown in J); 'exact' for a residual or a tolerance."""
    lowered = head.lower()
    if any(word in lowered for word in _NOT_RESULTS):
        return "exact"
    if "energy" in lowered and "share" not in lowered and "relative" not in lowered:
        return "energy"
    return None


def number(value: float | None, unit: str | None = None, kind: str | None = None, reference: float = 0.0) -> str:
    """One value on its own (a line of text): six significant figures, in the display unit of
    `unit` when given (its prefix chosen from the value itself), with that unit."""
    from flexmech.service.display import Display, display, exact  # with the models, when a command runs

    if not unit:
        return "-" if value is None else Display("").text(value)
    if kind == "exact":
        return exact(value, unit)
    return display(unit, [value], kind, reference).text(value, with_unit=True)


def exact_text(value: float | None, unit: str = "") -> str:
    """A residual or a tolerance: exactly (service.display.exact)."""
    from flexmech.service.display import exact

    return exact(value, unit)


def row_texts(values: list[float | None], unit: str, kind: str | None = None, reference: float = 0.0) -> list[str]:
    """Values of one quantity shown side by side (a design variable's start, optimum and
    bounds), each with its unit, in one display chosen from them all (service.display)."""
    from flexmech.service.display import display

    shown = display(unit, values, kind, reference)
    return [shown.text(value, with_unit=True) for value in values]


def _is_number(value: Any) -> bool:
    return value is None or isinstance(value, (int, float)) and not isinstance(value, bool)


class TextTable(Table):
    """A table whose text cells never carry a control character to the terminal (whoever
    forgot to pass a document's name through shown()), and whose number cells (given as
    numbers, not text) are shown in their column's display unit when the table is printed."""

    def __init__(self, *args, unit_column: tuple[int, int] | None = None, **options):
        super().__init__(*args, **options)
        self.unit_column = unit_column  # (value column, unit column) when units vary by row
        self._numbers: dict[tuple[int, int], float | None] = {}
        self._heads: dict[int, str] = {}
        self._row_units: list[str] | None = None  # the unit column as added
        self._shown_for = -1  # the row count the numbers were last shown for (rich measures, then renders)

    def add_column(self, header: Any = "", *args, raw: str | None = None, **options) -> None:  # type: ignore[override]
        """`raw`: the head as written (`header` is it made safe for rich markup)."""
        self._heads[len(self.columns)] = raw if raw is not None else str(header)
        super().add_column(header, *args, **options)

    def add_row(self, *renderables, **options) -> None:  # type: ignore[override]
        row = len(self.rows)
        cells = []
        for col, cell in enumerate(renderables):
            if _is_number(cell) and col < len(self.columns) and self.columns[col].justify == "right":
                self._numbers[(row, col)] = None if cell is None else float(cell)
                cells.append("-")
            else:
                cells.append(without_controls(cell) if isinstance(cell, str) else cell)
        super().add_row(*cells, **options)

    def _show_numbers(self) -> None:
        """Each numeric column's cells in its display (a column of its unit and kind shares one
        display with the other such columns of the table)."""
        from flexmech.service.display import display, exact

        if self._shown_for == len(self.rows):
            return
        self._shown_for = len(self.rows)
        by_column: dict[int, list[int]] = {}
        for row, col in self._numbers:
            by_column.setdefault(col, []).append(row)
        if self.unit_column is not None:
            self._show_by_row(*self.unit_column)
            by_column.pop(self.unit_column[0], None)
        groups: dict[tuple[str, str | None], list[int]] = {}
        for col in by_column:
            _, unit, _ = head_unit(self._heads.get(col, ""))
            groups.setdefault((unit, kind_of(self._heads.get(col, ""))), []).append(col)
        for (unit, kind), cols in groups.items():
            values = [self._numbers[(row, col)] for col in cols for row in by_column[col]]
            shown = None if kind == "exact" else display(unit, values, kind)
            for col in cols:
                name, _, bracket = head_unit(self._heads.get(col, ""))
                if shown is not None and unit and shown.unit != unit:
                    close = "]" if bracket == "[" else ")"
                    self.columns[col].header = escape(f"{name} {bracket}{shown.unit}{close}")
                for row in by_column[col]:
                    value = self._numbers[(row, col)]
                    text = exact(value) if shown is None else shown.text(value)
                    self.columns[col]._cells[row] = text

    def _show_by_row(self, value_column: int, unit_column: int) -> None:
        from flexmech.service.display import display

        cells = self.columns[unit_column]._cells
        if self._row_units is None:
            self._row_units = [str(cell) for cell in cells]
        rows = [row for row, col in self._numbers if col == value_column]
        by_unit: dict[str, list[int]] = {}
        for row in rows:
            by_unit.setdefault(self._row_units[row], []).append(row)
        for unit, members in by_unit.items():
            values = [self._numbers[(row, value_column)] for row in members]
            shown = display(unit, values, reference=ONE_UNIT_REFERENCE if unit else 0.0)
            for row in members:
                self.columns[value_column]._cells[row] = shown.text(self._numbers[(row, value_column)])
                cells[row] = escape(shown.unit)

    def __rich_console__(self, console, options):  # type: ignore[override]
        self._show_numbers()
        return super().__rich_console__(console, options)

    def __rich_measure__(self, console, options):  # type: ignore[override]
        self._show_numbers()
        return super().__rich_measure__(console, options)


def without_controls(text: str) -> str:
    if text.isprintable():
        return text
    return "".join(c if c in "\n\t" or unicodedata.category(c) != "Cc" else " " for c in text)
