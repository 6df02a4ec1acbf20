"""What the public functions return: results that keep their numbers (document units) and their
units, and print as tables in a terminal (repr) and in Jupyter (_repr_html_)."""

from __future__ import annotations

import html
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

SHOWN_ROWS = 12  # rows of a long table printed (spread over it, the first and the last among them)


def _number(value: Any) -> str:
    if value is None:
        return "-"
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        return str(value)
    if isinstance(value, (float, np.floating)):
        return f"{float(value):.6g}"
    return str(value)


def _spread(count: int) -> list[int]:
    if count <= SHOWN_ROWS:
        return list(range(count))
    return sorted({round(k * (count - 1) / (SHOWN_ROWS - 1)) for k in range(SHOWN_ROWS)})


@dataclass(frozen=True)
class Table:
    """A titled table of text cells (names as they are, numbers to 6 significant digits)."""

    title: str
    heads: Sequence[str]
    rows: Sequence[Sequence[Any]]
    note: str = ""

    def text(self) -> str:
        cells = [[_number(c) for c in row] for row in self.rows]
        widths = [max([len(h), *(len(r[k]) for r in cells)]) for k, h in enumerate(self.heads)]
        lines = [self.title, "  ".join(h.ljust(w) for h, w in zip(self.heads, widths))]
        lines += [
            "  ".join(c.ljust(w) if k == 0 else c.rjust(w) for k, (c, w) in enumerate(zip(r, widths))) for r in cells
        ]
        return "\n".join(lines + ([self.note] if self.note else []))

    def html(self) -> str:
        head = "".join(f"<th>{html.escape(h)}</th>" for h in self.heads)
        body = "".join(
            "<tr>" + "".join(f"<td>{html.escape(_number(c))}</td>" for c in row) + "</tr>" for row in self.rows
        )
        note = f"<p>{html.escape(self.note)}</p>" if self.note else ""
        return f"<p><b>{html.escape(self.title)}</b></p><table><tr>{head}</tr>{body}</table>{note}"


class Printed(ABC):
    """A result that prints as its tables."""

    @abstractmethod
    def tables(self) -> list[Table]:
        """The tables it prints as."""

    def __repr__(self) -> str:
        return "\n\n".join(t.text() for t in self.tables())

    def _repr_html_(self) -> str:
        return "".join(t.html() for t in self.tables())


@dataclass(repr=False)
class Solution(Printed):
    """An equilibrium: its status, Newton's iterations, and every output and body displacement
    in the document's units (`units` names each one's). `raw` is the solver's result
    (flexmech.service.solvers.equilibrium.EquilibriumResult)."""

    status: str
    iterations: int
    residual: float  # the largest unbalanced force, document force unit
    outputs: dict[str, float]
    units: dict[str, str]
    displacements: dict[str, float]
    raw: Any = field(repr=False)
    name: str = ""

    @property
    def converged(self) -> bool:
        return self.status == "converged"

    def tables(self) -> list[Table]:
        shown = [n for n in self.outputs if not n.startswith(("elements.", "reactions."))] or list(self.outputs)
        rows = [(n, self.outputs[n], self.units.get(n, "")) for n in shown]
        title = f"{self.name}: {self.status} after {self.iterations} iterations"
        note = f"(of {len(self.outputs)} outputs: .outputs has them all)" if len(shown) < len(self.outputs) else ""
        return [Table(title, ("output", "value", "unit"), rows, note)]


@dataclass(repr=False)
class Target(Printed):
    """The value of a numeric field (`input`) at which an output reaches `goal`: `value` in
    `unit` (the document's), and the equilibrium there (`solution`)."""

    status: str
    input: str
    value: float
    unit: str
    output: str
    goal: float
    output_unit: str
    solution: Solution

    @property
    def converged(self) -> bool:
        return self.status == "converged"

    def tables(self) -> list[Table]:
        row = (self.input, self.value, self.unit, f"{self.output} = {_number(self.goal)} {self.output_unit}")
        return [Table(f"target: {self.status}", ("field", "value", "unit", "where"), [row])]


@dataclass(repr=False)
class Sweep(Printed):
    """Equilibria along the values of one numeric field: `values` (its `unit`), and per output
    its values (`outputs`, in `units`), each point's status."""

    input: str
    unit: str
    values: np.ndarray
    outputs: dict[str, np.ndarray]
    units: dict[str, str]
    status: list[str]
    raw: Any = field(repr=False)

    def tables(self) -> list[Table]:
        named = [n for n in self.outputs if not n.startswith(("elements.", "reactions.", "bodies."))][:4]
        heads = (f"{self.input} [{self.unit}]", *(f"{n} [{self.units.get(n, '')}]" for n in named), "status")
        rows = [
            (self.values[i], *(self.outputs[n][i] for n in named), self.status[i]) for i in _spread(len(self.values))
        ]
        converged = sum(s == "converged" for s in self.status)
        note = f"{len(self.values)} points, {converged} converged" + (
            " (spread evenly: .values and .outputs have them all)" if len(rows) < len(self.values) else ""
        )
        return [Table(f"sweep of {self.input}", heads, rows, note)]


@dataclass(repr=False)
class Report(Printed):
    """An analysis' report (the same as /v1/solve answers): `report` the JSON-able dict, and the
    fields a table shows."""

    report: dict[str, Any]
    table: Table

    @property
    def status(self) -> str:
        return str(self.report.get("status"))

    def __getitem__(self, key: str) -> Any:
        return self.report[key]

    def tables(self) -> list[Table]:
        return [self.table]
