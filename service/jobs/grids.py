"""The values a swept or path field takes (listed, or start to stop in equal steps), counted
before they are made, and the grid of several: its shape, a point's values, and the load paths
through it (service.jobs.sweep, service.contact.path)."""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import Protocol

import numpy as np

from flexmech.models import MechanismError
from flexmech.service.costs import Limits, check_grid_size


class Ranged(Protocol):
    """A field's values as a request or a document gives them (SweepParameter, PathParameter)."""

    path: str
    values: list[float] | None
    start: float | None
    stop: float | None
    steps: int | None


def value_count(parameter: Ranged, pointer: str, until: bool = False) -> int:
    """How many values a parameter takes, without making them (with `until`, no stop)."""
    if parameter.values is not None:
        return len(parameter.values)
    needed = {"start": parameter.start, "steps": parameter.steps, **({} if until else {"stop": parameter.stop})}
    if any(value is None for value in needed.values()):
        raise MechanismError(
            pointer,
            "give start and steps (the stop is found by until)" if until else "give values, or start, stop and steps",
        )
    steps = parameter.steps
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise MechanismError(f"{pointer}/steps", "must be a whole number of at least 1")
    return steps + 1


def parameter_values(parameter: Ranged, pointer: str, stop: float | None = None) -> list[float]:
    """Its values; `stop` (found by until) over the parameter's own."""
    if parameter.values is not None:
        values = [float(v) for v in parameter.values]
    else:
        value_count(parameter, pointer, until=stop is not None)
        last = float(parameter.stop if stop is None else stop)  # type: ignore[arg-type]
        values = np.linspace(float(parameter.start), last, int(parameter.steps) + 1).tolist()  # type: ignore[arg-type]
    if not values:
        raise MechanismError(f"{pointer}/values", "no values")
    if not all(np.isfinite(values)):
        raise MechanismError(f"{pointer}/values", "values must be finite numbers")
    return values


def grid_size(parameters: Sequence[Ranged], grid: str, limits: Limits, until: bool = False) -> int:
    """The number of points, checked against the limit before any value is made."""
    counts = [value_count(p, f"/parameters/{k}", until) for k, p in enumerate(parameters)]
    if grid == "zip":
        if len(set(counts)) > 1:
            raise MechanismError(
                "/parameters",
                f"a zip grid needs equally many values per parameter (got {', '.join(str(c) for c in counts)})",
            )
        counts = counts[:1]
    return check_grid_size(counts, limits)


def grid_shape(
    parameters: Sequence[Ranged], grid: str, stop: float | None = None
) -> tuple[list[list[float]], tuple[int, ...]]:
    """(values per parameter, grid shape); zip grids have shape (n,). Call grid_size first.
    `stop`: the one parameter's stop, found by until."""
    values = [parameter_values(p, f"/parameters/{k}", stop) for k, p in enumerate(parameters)]
    if grid == "zip":
        lengths = {len(v) for v in values}
        if len(lengths) > 1:
            raise MechanismError(
                "/parameters",
                f"a zip grid needs equally many values per parameter (got {', '.join(str(len(v)) for v in values)})",
            )
        return values, (len(values[0]),)
    return values, tuple(len(v) for v in values)


def point_values(values: list[list[float]], shape: tuple[int, ...], grid: str, index: int) -> list[float]:
    if grid == "zip":
        return [v[index] for v in values]
    multi = np.unravel_index(index, shape)
    return [v[int(m)] for v, m in zip(values, multi)]


def load_paths(paths: Sequence[str], grid: str, continuation: str | None, shape: tuple[int, ...]) -> list[list[int]]:
    """Point indices in solving order: one list per load path (along `continuation`, one of the
    swept `paths`), else one list per point."""
    total = int(np.prod(shape))
    if continuation is None:
        return [[i] for i in range(total)]
    if grid == "zip":
        return [list(range(total))]
    axis = list(paths).index(continuation)
    others = [range(n) for k, n in enumerate(shape) if k != axis]
    lines = []
    for rest in itertools.product(*others):
        line = []
        for t in range(shape[axis]):
            multi = list(rest)
            multi.insert(axis, t)
            line.append(int(np.ravel_multi_index(multi, shape)))
        lines.append(line)
    return lines
