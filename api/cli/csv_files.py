"""The --csv files: a simulation's time histories and a sweep's points as one table each, a
column per quantity and a row per kept state or point, for a spreadsheet or pandas.

The header row names each column with its unit in brackets (`t [s]`, `tip.y [m]`; a column
without a unit, like a status, has none), the units those of the report (document units). The
numbers are written in full (Python's shortest repr that reads back exactly), so a cell equals
the --json file's number; a non-finite number (null in --json) is an empty cell."""

from __future__ import annotations

import csv
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from flexmech.api.cli.common import OptionError

Column = tuple[str, list[Any]]  # (header, one value per row)


def heading(name: str, unit: str | None) -> str:
    """`name [unit]`, or the name alone when it has no unit."""
    return f"{name} [{unit}]" if unit else name


def cell(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return ""
    return "" if value is None else value


def write_csv(path: Path, columns: list[Column], option: str = "--csv") -> None:
    """Write the columns (each as long as the first) as a CSV file; OptionError names the option
    when it cannot be written."""
    rows = len(columns[0][1]) if columns else 0
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with path.open("w", newline="") as file:
            writer = csv.writer(file)
            writer.writerow([head for head, _ in columns])
            writer.writerows([cell(values[k]) for _, values in columns] for k in range(rows))
    except OSError as exc:
        raise OptionError(option, f"cannot write {path}: {exc.strerror}") from None


def history_columns(report: dict[str, Any]) -> list[Column]:
    """A simulation report's histories: the time, then each output (link schemes: `outputs`,
    the constraint and motion forces; impact schemes: each body's coordinates and velocities,
    each contact pair's and joint's fields), then the energies and works. Series not one per
    kept time are left out."""
    units, series = report.get("units", {}), report.get("series_units", {})
    output_units = report.get("output_units", {})
    times = report["times"]
    columns: list[Column] = [(heading("t", units.get("time", "s")), times)]
    named: list[tuple[str, str | None, list[Any]]] = []
    named += [(name, output_units.get(name), values) for name, values in report.get("outputs", {}).items()]
    for group in ("constraint_forces", "motion_forces"):
        named += [(name, series.get(name), values) for name, values in report.get(group, {}).items()]
    named += [(name, series.get(name), values) for name, values in report.get("coordinates", {}).items()]
    for name, values in report.get("velocities", {}).items():
        named.append((f"{name}.velocity", series.get(f"{name}.velocity"), values))
    for group in ("contacts", "joints"):
        for owner, fields in report.get(group, {}).items():
            named += [(f"{owner}.{field}", series.get(f"{owner}.{field}"), v) for field, v in fields.items()]
    named += [(f"energies.{name}", units.get("energy"), v) for name, v in report.get("energies", {}).items()]
    columns += [(heading(name, unit), values) for name, unit, values in named if len(values) == len(times)]
    return columns


def sweep_columns(path: str, unit: str, output_units: dict[str, str], records: list[dict[str, Any]]) -> list[Column]:
    """The points of a sweep's curves (their --json records): the swept field, each output, the
    status and the Newton iterations of each point; with several curves (--compare-models) a
    first column names each row's curve, and the outputs are those every curve has."""
    curves = [record for record in records if "sweep" in record]  # a curve whose target was not reached has none
    outputs = [  # those of every curve (the models' flexures report different ones)
        name
        for name in (curves[0]["sweep"]["outputs"] if curves else [])
        if all(name in c["sweep"]["outputs"] for c in curves)
    ]

    def joined(values_of: Callable[[dict[str, Any]], list[Any]]) -> list[Any]:
        return [value for record in curves for value in values_of(record["sweep"])]

    columns: list[Column] = []
    if len(curves) > 1:
        columns.append(("curve", [record["label"] for record in curves for _ in record["sweep"]["values"]]))
    columns.append((heading(path, unit), joined(lambda s: s["values"])))
    for name in outputs:
        columns.append((heading(name, output_units.get(name)), joined(lambda s, n=name: s["outputs"][n])))
    columns += [("status", joined(lambda s: s["status"])), ("iterations", joined(lambda s: s["iterations"]))]
    return columns
