"""The sweep job: numeric fields of a document varied over a grid.

spec:
  document      the mechanism document (JSON object)
  parameters    [{path, values} | {path, start, stop, steps}], document units
  grid          "cartesian" (every combination; the first parameter varies slowest) | "zip"
  continuation  optional path of one parameter: the points along it (the others held) form a
                load path solved in order, each from the previous converged state, in tasks
                of chunk_size points one after another; without it every point starts from
                the undeformed state and chunks run in parallel
  until         optional {output, equals}: one ranged parameter (start, steps) runs from start
                to the value at which the output equals `equals` (solved for first, as the
                equilibrium's target, when the job is created): that value is its stop
  outputs       optional output names to keep (default: all)
  analysis      the sweepable analysis of every point (default: equilibrium)
  model, options, overrides   as for /v1/solve

Point index = position in the grid (row-major over `parameters`); each task carries its points'
values (the plan's, which hold the stop `until` found). Each stored point keeps its
nondimensional state z, so a load path resumed after a restart starts from exactly the state
an uninterrupted run would have used, and gives the same numbers.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Mapping
from functools import lru_cache

import numpy as np

from models import Mechanism, MechanismError
from service.analyses import ANALYSES
from service.costs import Limits, check_grid_size, check_result_size
from service.equilibrium import check_constrained
from service.jobs.base import Plan
from service.jobs.control import TaskControl
from service.reports import output_units, plain
from service.requests import compile_request, newton_options
from service.sweep import solve_for_target
from service.units import residual_report


def value_count(parameter: dict, pointer: str, until: bool = False) -> int:
    """How many values a parameter takes, without making them (with `until`, no stop)."""
    if parameter.get("values") is not None:
        return len(parameter["values"])
    missing = [k for k in ("start", "steps", *(() if until else ("stop",))) if parameter.get(k) is None]
    if missing:
        raise MechanismError(
            pointer,
            "give start and steps (the stop is found by until)" if until else "give values, or start, stop and steps",
        )
    steps = parameter["steps"]
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise MechanismError(f"{pointer}/steps", "must be a whole number of at least 1")
    return steps + 1


def parameter_values(parameter: dict, pointer: str, stop: float | None = None) -> list[float]:
    """Its values; `stop` (found by until) over the parameter's own."""
    if parameter.get("values") is not None:
        values = [float(v) for v in parameter["values"]]
    else:
        value_count(parameter, pointer, until=stop is not None)
        last = float(parameter["stop"] if stop is None else stop)
        values = np.linspace(float(parameter["start"]), last, int(parameter["steps"]) + 1).tolist()
    if not values:
        raise MechanismError(f"{pointer}/values", "no values")
    if not all(np.isfinite(values)):
        raise MechanismError(f"{pointer}/values", "values must be finite numbers")
    return values


def grid_size(spec: dict, limits: Limits) -> int:
    """The number of points, checked against the limit before any value is made."""
    until = spec.get("until") is not None
    counts = [value_count(p, f"/parameters/{k}", until) for k, p in enumerate(spec["parameters"])]
    if spec.get("grid", "cartesian") == "zip":
        if len(set(counts)) > 1:
            raise MechanismError(
                "/parameters",
                f"a zip grid needs equally many values per parameter (got {', '.join(str(c) for c in counts)})",
            )
        counts = counts[:1]
    return check_grid_size(counts, limits)


def grid_shape(spec: dict, stop: float | None = None) -> tuple[list[list[float]], tuple[int, ...]]:
    """(values per parameter, grid shape); zip grids have shape (n,). Call grid_size first.
    `stop`: the one parameter's stop, found by until."""
    values = [parameter_values(p, f"/parameters/{k}", stop) for k, p in enumerate(spec["parameters"])]
    if spec.get("grid", "cartesian") == "zip":
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


def load_paths(spec: dict, shape: tuple[int, ...]) -> list[list[int]]:
    """Point indices in solving order: one list per load path (continuation), else one list per
    point."""
    total = int(np.prod(shape))
    path = spec.get("continuation")
    if path is None:
        return [[i] for i in range(total)]
    if spec.get("grid", "cartesian") == "zip":
        return [list(range(total))]
    axis = [p["path"] for p in spec["parameters"]].index(path)
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


@lru_cache(maxsize=16)
def _mechanism(document_json: str, model: str | None, overrides_json: str) -> Mechanism:
    """One compiled mechanism per document in each worker process; its CasADi Functions are
    built once per structure (models.assembly.graphs_for is cached) and reused by every task."""
    return compile_request(json.loads(document_json), model, json.loads(overrides_json))


def mechanism_of(spec: dict) -> Mechanism:
    return _mechanism(
        json.dumps(spec["document"], sort_keys=True),
        spec.get("model"),
        json.dumps(spec.get("overrides") or {}, sort_keys=True),
    )


def until_stop(spec: dict, mech: Mechanism) -> tuple[float | None, dict | None]:
    """(the stop `until` finds, what to report of it), or (None, None) without until. Its
    output's value is reached by the one ranged parameter, solved for as the equilibrium's
    target is (from the document's state); a target not reached is a 422 saying so."""
    until = spec.get("until")
    if until is None:
        return None, None
    parameters = spec["parameters"]
    if len(parameters) != 1 or parameters[0].get("values") is not None:
        raise MechanismError("/until", "until stops one ranged parameter (start and steps): give one")
    if parameters[0].get("stop") is not None:
        raise MechanismError("/parameters/0/stop", "until finds the stop: give stop or until, not both")
    path = parameters[0]["path"]
    try:
        mech.parameter_index(path)
    except MechanismError as exc:
        raise MechanismError("/parameters/0/path", exc.problem) from None
    if until["output"] not in mech.graphs.output_names:
        raise MechanismError("/until/output", f"unknown output '{until['output']}'")
    options = newton_options(spec.get("options"))
    found = solve_for_target(mech, path, until["output"], float(until["equals"]), options)
    if found.status != "converged":
        raise MechanismError(
            "/until",
            f"the value at which {until['output']} = {until['equals']:g} was not found "
            f"({found.status}: {found.equilibrium.message})",
        )
    return found.value, {
        "output": until["output"],
        "equals": until["equals"],
        "path": path,
        "value": found.value,
        "unit": mech.doc_unit(mech.parameter_kind(path)),
    }


def _check_spec(
    spec: dict, limits: Limits, stop: float | None = None
) -> tuple[list[list[float]], tuple[int, ...], list[str]]:
    """The grid (values per parameter, shape) and the swept paths of a valid spec."""
    grid_size(spec, limits)
    values, shape = grid_shape(spec, stop)
    paths = [p["path"] for p in spec["parameters"]]
    if len(set(paths)) != len(paths):
        raise MechanismError("/parameters", "a path is listed twice")
    if spec.get("continuation") is not None and spec["continuation"] not in paths:
        raise MechanismError(
            "/continuation", f"'{spec['continuation']}' is not one of the swept paths ({', '.join(paths)})"
        )
    analysis = ANALYSES.named(spec.get("analysis") or "equilibrium")
    if not analysis.sweepable:
        sweepable = ", ".join(a["name"] for a in ANALYSES.describe() if a["sweepable"])
        raise MechanismError(
            "/analysis", f"the {analysis.name} analysis has no points to sweep (sweepable: {sweepable})"
        )
    return values, shape, paths


class SweepJob:
    name = "sweep"
    paged = True

    def prepare(self, spec: dict, limits: Limits) -> Plan:
        grid_size(spec, limits)  # before any solve
        mech = compile_request(spec["document"], spec.get("model"), spec.get("overrides"), limits)
        newton_options(spec.get("options"))
        stop, until = until_stop(spec, mech)
        values, shape, paths = _check_spec(spec, limits, stop)
        units = []
        for k, path in enumerate(paths):
            try:
                units.append(mech.doc_unit(mech.parameter_kind(path)))
            except MechanismError as exc:
                raise MechanismError(f"/parameters/{k}/path", exc.problem) from None
        for k, (path, parameter_values_k) in enumerate(zip(paths, values)):
            for i, value in enumerate(parameter_values_k):  # the same checks as the document's own
                where = (
                    f"/parameters/{k}/values/{i}"
                    if spec["parameters"][k].get("values") is not None
                    else f"/parameters/{k}"
                )
                mech.checked_si(path, value, where)
        all_units = output_units(mech)
        wanted = spec.get("outputs") or list(all_units)
        for k, name in enumerate(wanted):
            if name not in all_units:
                raise MechanismError(f"/outputs/{k}", f"unknown output '{name}'")
        stored = len(wanted) + (mech.n_free if spec.get("continuation") is not None else 0)
        check_result_size(int(np.prod(shape)), stored, limits)
        try:
            check_constrained(mech)
        except MechanismError as exc:
            raise MechanismError("/document" + exc.pointer, exc.problem) from None
        meta = {
            "parameters": [{"path": p, "unit": u, "values": v} for p, u, v in zip(paths, units, values)],
            "shape": list(shape),
            "output_units": {n: all_units[n] for n in wanted},
            "force_unit": mech.doc_unit("force"),
            "moment_unit": mech.doc_unit("moment"),
            "solve_time_limit": limits.solve_time_limit,
            **({"until": until} if until else {}),
        }
        return Plan(int(np.prod(shape)), meta)

    def failed(self, point: dict) -> bool:
        return point.get("status") != "converged"

    def tasks(self, spec, plan, finished, chunk_size):
        tasks = []
        lines = load_paths(spec, tuple(plan["shape"]))
        if spec.get("continuation") is None:
            todo = [line[0] for line in lines if line[0] not in finished]
            for start in range(0, len(todo), chunk_size):
                tasks.append({"indices": todo[start : start + chunk_size], "guess": None})
        else:
            for number, line in enumerate(lines):
                task = self._next_on_line(line, number, finished, chunk_size)
                if task is not None:
                    tasks.append(task)
        return [self._with_values(t, spec, plan) for t in tasks]

    def follow_up(self, spec, plan, task, finished, chunk_size):
        if task.get("line") is None:
            return []
        line = load_paths(spec, tuple(plan["shape"]))[task["line"]]
        nxt = self._next_on_line(line, task["line"], finished, chunk_size)
        return [self._with_values(nxt, spec, plan)] if nxt is not None else []

    @staticmethod
    def _with_values(task: dict, spec: dict, plan: Mapping) -> dict:
        """The task with its points' values (the plan's grid) and the solve time limit."""
        values = [p["values"] for p in plan["parameters"]]
        grid, shape = spec.get("grid", "cartesian"), tuple(plan["shape"])
        return task | {
            "time_limit": plan.get("solve_time_limit"),
            "values": [point_values(values, shape, grid, i) for i in task["indices"]],
        }

    @staticmethod
    def _next_on_line(line: list[int], number: int, finished: Mapping[int, dict], chunk_size: int) -> dict | None:
        """The next chunk of a load path: from its first unfinished point, starting from the
        state of the last converged point before it (undeformed if none)."""
        position = next((k for k, i in enumerate(line) if i not in finished), None)
        if position is None:
            return None
        guess = None
        for i in reversed(line[:position]):
            if finished[i]["status"] == "converged":
                guess = finished[i]["z"]
                break
        return {"indices": line[position : position + chunk_size], "guess": guess, "line": number}

    def run(self, spec, task):
        mech = mechanism_of(spec)
        analysis = ANALYSES.named(spec.get("analysis") or "equilibrium")
        control = TaskControl(task)
        if task.get("values") is not None:
            at = dict(zip(task["indices"], task["values"]))
        else:  # a task stored before tasks carried their values: the grid again (no until then)
            values, shape = grid_shape(spec)
            at = {i: point_values(values, shape, spec.get("grid", "cartesian"), i) for i in task["indices"]}
        slots = [mech.parameter_index(p["path"]) for p in spec["parameters"]]
        factors = [mech.nd_per_doc(mech.parameters[k].kind) for k in slots]
        names, kinds = mech.graphs.output_names, mech.graphs.output_kinds
        wanted = spec.get("outputs") or list(names)
        columns = [(names.index(n), mech.nd_per_doc(kinds[names.index(n)])) for n in wanted]
        p0 = mech.p()
        zero = np.zeros(mech.n_free)
        z_prev = np.asarray(task["guess"], dtype=float) if task.get("guess") is not None else zero
        along_path = task.get("line") is not None
        points = []
        for index in task["indices"]:
            if control.should_stop():  # cancelled, or out of the job's time: the runner drops the rest
                break
            options = newton_options(spec.get("options"), control.time_limit(task.get("time_limit")))
            here = at[index]
            p = p0.copy()
            p[slots] = np.asarray(here) * factors
            r = analysis.point(mech, p, z_prev if along_path else zero, options)
            if along_path and r.converged:
                z_prev = r.z
            y = np.asarray(mech.graphs.outputs(r.z, p)).ravel()
            residuals = residual_report(mech, r.z, p)
            points.append(
                (
                    index,
                    plain(
                        {
                            "values": here,
                            "status": r.status,
                            "message": r.message,
                            "iterations": r.iterations,
                            **{k: residuals[k] for k in ("residual_norm", "residual_moment", "solver_residual")},
                            "seconds": r.seconds,
                            "outputs": {n: y[j] / f for n, (j, f) in zip(wanted, columns)},
                            **({"z": r.z} if along_path else {}),  # the state a resumed load path starts from
                        }
                    ),
                )
            )
        return points

    def result(self, spec, plan, finished):
        points = [{"index": i, **{k: v for k, v in d.items() if k != "z"}} for i, d in sorted(finished.items())]
        return {
            "parameters": plan["parameters"],
            "grid": spec.get("grid", "cartesian"),
            "continuation": spec.get("continuation"),
            "output_units": plan["output_units"],
            "residual_unit": plan["force_unit"],
            "residual_moment_unit": plan.get("moment_unit"),
            "analysis": spec.get("analysis") or "equilibrium",
            "points": points,
            **({"until": plan["until"]} if plan.get("until") else {}),
        }


SWEEP = SweepJob()
