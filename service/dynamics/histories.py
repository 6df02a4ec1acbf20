"""Loads and prescribed motions that change in time: a history per numeric field, keyed by
its JSON pointer (as sweeps name fields), in the field's document unit, with t in seconds:

    "/loads/drive/moment": {"table": [[0, 0], [0.2, 100], [0.4, 100], [0.6, 0]]}
    "/loads/spin/rotation": {"pieces": [{"until": 15, "value": "2/15*(t**2/2 + ...)"},
                                        {"value": "2*(t - 7.5)"}]}
    "/loads/hold/force/1": "10.99*exp(-t/0.01)"      (or a number: a constant)

Expressions are the safe ones of models.documents.expression, in t. A table is linear between its
points and constant beyond them (loads only: a motion needs an acceleration, so it takes an
expression or pieces whose values and rates meet at the joins). The document's own value
of a field is its value before the run: a start from equilibrium uses it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.documents.expression import compile_expression

MAX_TABLE = 100_000
MAX_INLINE_TABLE = 200  # a table inside a step graph (impact simulations)
VARYING = ("force", "moment", "dx", "dy", "rotation")


@dataclass(frozen=True)
class Histories:
    indices: tuple[int, ...]  # parameters that vary (loads and motions)
    moving: tuple[int, ...]  # of them, the prescribed motions
    smooth: ca.Function  # t -> (values of `indices`, rates and accelerations of `moving`)
    tables: tuple[tuple[int, np.ndarray, np.ndarray], ...]  # (index, times, values) of tabled loads

    def at(self, p: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(p at t, rates, accelerations of the moving parameters), nondimensional."""
        out = p.copy()
        values, rates, accelerations = self.smooth(t)
        out[list(self.indices)] = np.asarray(values, dtype=float).ravel()
        for index, times, table in self.tables:
            out[index] = np.interp(t, times, table)
        return out, np.asarray(rates, dtype=float).ravel(), np.asarray(accelerations, dtype=float).ravel()

    def at_times(self, p: np.ndarray, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """at() for many times in one call: columns of p, of the rates and of the accelerations."""
        out = np.repeat(p[:, None], len(times), axis=1)
        values, rates, accelerations = (np.asarray(q, dtype=float) for q in _mapped(self.smooth, len(times))(times))
        out[list(self.indices), :] = values.reshape(len(self.indices), len(times))
        for index, table_times, table in self.tables:
            out[index, :] = np.interp(times, table_times, table)
        k = len(self.moving)
        return out, rates.reshape(k, len(times)), accelerations.reshape(k, len(times))

    def load_mask(self, n_parameters: int) -> np.ndarray:
        """1 at the loads that vary (their work is an input), else 0."""
        mask = np.zeros(n_parameters)
        mask[list(set(self.indices) - set(self.moving)) + [index for index, _, _ in self.tables]] = 1.0
        return mask


@lru_cache(maxsize=64)
def _mapped(function: ca.Function, count: int) -> ca.Function:
    return function.map(count)


def varying_values(mech: Mechanism, histories: Histories, p: list[np.ndarray]) -> dict:
    """The fields that histories drive (loads and motions), in document units at each kept
    state's parameters `p`, with their units: {"values": {pointer: [...]}, "units": {...}}.
    The page draws a frame's loads from them, not from the document's values."""
    indices = sorted(set(histories.indices) | {index for index, _, _ in histories.tables})
    values, units = {}, {}
    for index in indices:
        parameter = mech.parameters[index]
        scale = mech.nd_per_doc(parameter.kind)
        values[parameter.pointer] = [float(q[index]) / scale for q in p]
        units[parameter.pointer] = mech.doc_unit(parameter.kind)
    return {"values": values, "units": units}


def no_histories() -> Histories:
    t = ca.SX.sym("t")
    return Histories((), (), ca.Function("histories", [t], [ca.SX(0, 1), ca.SX(0, 1), ca.SX(0, 1)]), ())


def read_histories(mech: Mechanism, spec: dict | None, until: float, pointer: str = "/histories") -> Histories:
    """The histories of a request, checked: each names a load's or a motion's numeric field,
    parses safely and is finite over [0, until]."""
    if not spec:
        return no_histories()
    if not isinstance(spec, dict):
        raise MechanismError(pointer, "expected an object: field pointer -> history")
    motions = {row[c]: (b, c) for b, row in enumerate(mech.structure.prescribed) for c in range(3) if row[c]}
    t = ca.SX.sym("t")
    smooth_indices, smooth_values, tables, moving = [], [], [], []
    for path, history in spec.items():
        path = path if path.startswith("/") else f"/{path}"
        where = f"{pointer}/{path.lstrip('/').replace('~', '~0').replace('/', '~1')}"
        index = _varying_field(mech, path, where)
        scale = mech.nd_per_doc(mech.parameters[index].kind)
        if path in motions:
            moving.append(index)
            _check_unloaded(mech, path, motions[path], where)
        if isinstance(history, dict) and "table" in history:
            if path in motions:
                raise MechanismError(
                    f"{where}/table",
                    "a prescribed motion needs an acceleration: give an expression "
                    "or pieces, not a table (a table's rate jumps at its points)",
                )
            times, values = _table(history["table"], f"{where}/table")
            tables.append((index, times, values * scale))
            continue
        expression = _smooth(history, t, where)
        _finite(expression, t, until, where)
        if path in motions:
            _joins_meet(history, expression, t, where)
        smooth_indices.append(index)
        smooth_values.append(expression * scale)
    order = [smooth_indices.index(k) for k in moving]
    values = ca.vertcat(*smooth_values) if smooth_values else ca.SX(0, 1)
    motion = ca.vertcat(*[values[k] for k in order]) if order else ca.SX(0, 1)
    rates = ca.jacobian(motion, t)
    smooth = ca.Function("histories", [t], [values, rates, ca.jacobian(rates, t)])
    return Histories(tuple(smooth_indices), tuple(moving), smooth, tuple(tables))


def _varying_field(mech: Mechanism, path: str, where: str) -> int:
    try:
        index = mech.parameter_index(path)
    except MechanismError as exc:
        raise MechanismError(where, f"'{path}' is {exc.problem}") from None
    parts = path.strip("/").split("/")
    if not (parts[0] == "gravity" or (parts[0] == "loads" and len(parts) >= 3 and parts[2] in VARYING)):
        raise MechanismError(
            where,
            f"'{path}' cannot change in time: only loads (force, moment), prescribed "
            "displacements (dx, dy, rotation) and gravity can",
        )
    return index


def _check_unloaded(mech: Mechanism, path: str, coordinate: tuple[int, int], where: str) -> None:
    """A coordinate moved in time takes whatever force its motion needs: a load on it would
    do no work the run could report."""
    b, c = coordinate
    body = mech.structure.bodies[b]
    for load in mech.structure.loads:
        acts = (c < 2) if load.kind == "force" else (c == 2)
        if load.body == b and acts:
            coordinate_name = ("x", "y", "angle")[c]
            raise MechanismError(
                where,
                f"{body}.{coordinate_name} is prescribed in time by '{path}' and also loaded by "
                f"/loads/{load.name}: remove the load or the motion",
            )


def history_expression(history, t: ca.SX, where: str, until: float) -> ca.SX:
    """A history as an expression of t (a table, linear between its rows, with at most
    MAX_INLINE_TABLE rows), checked finite over [0, until]; in the field's document unit."""
    if isinstance(history, dict) and "table" in history:
        times, values = _table(history["table"], f"{where}/table")
        if len(times) > MAX_INLINE_TABLE:
            raise MechanismError(
                f"{where}/table", f"at most {MAX_INLINE_TABLE} rows here: give an expression or pieces"
            )
        expression = ca.SX(float(values[-1]))
        for k in range(len(times) - 2, -1, -1):
            slope = (values[k + 1] - values[k]) / (times[k + 1] - times[k])
            expression = ca.if_else(t < times[k + 1], values[k] + slope * (t - times[k]), expression)
        expression = ca.if_else(t < times[0], float(values[0]), expression)
    else:
        expression = _smooth(history, t, where)
    _finite(expression, t, until, where)
    return expression


def _smooth(history, t: ca.SX, where: str) -> ca.SX:
    if isinstance(history, (int, float)) and not isinstance(history, bool):
        return ca.SX(float(history))
    if isinstance(history, str):
        return compile_expression(history, where, variable="t")(t)
    if isinstance(history, dict) and "pieces" in history:
        pieces = history["pieces"]
        if not isinstance(pieces, list) or not pieces:
            raise MechanismError(f"{where}/pieces", 'expected a list of pieces {"until": t, "value": expression}')
        ends = [piece.get("until") if isinstance(piece, dict) else None for piece in pieces[:-1]]
        if any(not isinstance(end, (int, float)) for end in ends) or any(b <= a for a, b in zip(ends, ends[1:])):
            raise MechanismError(f"{where}/pieces", 'every piece but the last needs "until" (s), increasing')
        exprs = [
            _smooth(piece.get("value") if isinstance(piece, dict) else None, t, f"{where}/pieces/{k}/value")
            for k, piece in enumerate(pieces)
        ]
        out = exprs[-1]
        for end, expr in zip(reversed(ends), reversed(exprs[:-1])):
            out = ca.if_else(t < end, expr, out)
        return out
    raise MechanismError(
        where,
        'expected a number, an expression in t, {"table": [[t, value], ...]} or '
        '{"pieces": [{"until": t, "value": expression}, ...]}',
    )


def _table(rows, where: str) -> tuple[np.ndarray, np.ndarray]:
    try:
        table = np.asarray(rows, dtype=float)
    except (TypeError, ValueError):
        raise MechanismError(where, "expected rows [t, value] of numbers") from None
    if table.ndim != 2 or table.shape[1] != 2 or len(table) < 1 or len(table) > MAX_TABLE:
        raise MechanismError(where, f"expected 1 to {MAX_TABLE} rows [t, value]")
    if not np.all(np.isfinite(table)):
        raise MechanismError(where, "the table has a value that is not a finite number")
    if np.any(np.diff(table[:, 0]) <= 0):
        raise MechanismError(where, "the times must increase")
    return table[:, 0], table[:, 1]


def _finite(expression: ca.SX, t: ca.SX, until: float, where: str) -> None:
    times = np.linspace(0.0, until, 1001)
    f = ca.Function("history", [t], [expression, ca.jacobian(expression, t)]).map(len(times))
    values, rates = (np.asarray(q, dtype=float).ravel() for q in f(times))
    bad = np.flatnonzero(~(np.isfinite(values) & np.isfinite(rates)))
    if len(bad):
        raise MechanismError(
            where,
            f"the history is not a finite number at t = {times[bad[0]]:g} s (a division by "
            "zero, an overflow, or a root or logarithm of a negative number)",
        )


def _joins_meet(history, expression: ca.SX, t: ca.SX, where: str) -> None:
    if not (isinstance(history, dict) and "pieces" in history):
        return
    f = ca.Function("motion", [t], [expression, ca.jacobian(expression, t)])
    for end in (piece["until"] for piece in history["pieces"][:-1]):
        before, after = (np.array([float(q) for q in f(end + side * 1e-9 * max(1.0, abs(end)))]) for side in (-1, 1))
        size = max(1.0, *np.abs(before))
        if np.any(np.abs(after - before) > 1e-6 * size):
            raise MechanismError(
                f"{where}/pieces",
                f"the motion's value or rate jumps at t = {end:g} s "
                f"(from {before[0]:.6g}, {before[1]:.6g} to {after[0]:.6g}, {after[1]:.6g}): "
                "a prescribed motion must be smooth",
            )
