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

import json
from collections.abc import Mapping
from functools import lru_cache
from typing import Any

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.service.analyses import ANALYSES
from flexmech.service.costs import Limits, check_result_size
from flexmech.service.jobs.base import JSON, Plan, StoredJob, read_spec, unfinished_part
from flexmech.service.jobs.control import TaskControl
from flexmech.service.jobs.grids import grid_shape, grid_size, load_paths, point_values
from flexmech.service.jobs.sweep_options import SWEEP_EXAMPLES, SweepOptions, SweepSpec
from flexmech.service.requests import compile_request, newton_options
from flexmech.service.solvers.equilibrium import check_constrained
from flexmech.service.solvers.reports import output_units, plain
from flexmech.service.solvers.sweep import solve_for_target
from flexmech.service.units import residual_report


@lru_cache(maxsize=16)
def _mechanism(document_json: str, model: str | None, overrides_json: str) -> Mechanism:
    """One compiled mechanism per document in each worker process; its CasADi Functions are
    built once per structure (models.graph.assembly.graphs_for is cached) and reused by every task."""
    return compile_request(json.loads(document_json), model, json.loads(overrides_json))


def mechanism_of(spec: StoredJob) -> Mechanism:
    return _mechanism(
        json.dumps(spec.document, sort_keys=True), spec.model, json.dumps(spec.overrides or {}, sort_keys=True)
    )


def until_stop(spec: SweepSpec, mech: Mechanism) -> tuple[float | None, dict[str, Any] | None]:
    """(the stop `until` finds, what to report of it), or (None, None) without until. Its
    output's value is reached by the one ranged parameter, solved for as the equilibrium's
    target is (from the document's state); a target not reached is a 422 saying so."""
    until = spec.until
    if until is None:
        return None, None
    parameters = spec.parameters
    if len(parameters) != 1 or parameters[0].values is not None:
        raise MechanismError("/until", "until stops one ranged parameter (start and steps): give one")
    if parameters[0].stop is not None:
        raise MechanismError("/parameters/0/stop", "until finds the stop: give stop or until, not both")
    path = parameters[0].path
    try:
        mech.parameter_index(path)
    except MechanismError as exc:
        raise MechanismError("/parameters/0/path", exc.problem) from None
    if until.output not in mech.graphs.output_names:
        raise MechanismError("/until/output", f"unknown output '{until.output}'")
    found = solve_for_target(mech, path, until.output, until.equals, newton_options(spec.options))
    if found.status != "converged":
        raise MechanismError(
            "/until",
            f"the value at which {until.output} = {until.equals:g} was not found "
            f"({found.status}: {found.equilibrium.message})",
        )
    return found.value, {
        "output": until.output,
        "equals": until.equals,
        "path": path,
        "value": found.value,
        "unit": mech.doc_unit(mech.parameter_kind(path)),
    }


def _check_spec(
    spec: SweepSpec, limits: Limits, stop: float | None = None
) -> tuple[list[list[float]], tuple[int, ...], list[str]]:
    """The grid (values per parameter, shape) and the swept paths of a valid spec."""
    grid_size(spec.parameters, spec.grid, limits, spec.until is not None)
    values, shape = grid_shape(spec.parameters, spec.grid, stop)
    paths = [p.path for p in spec.parameters]
    if len(set(paths)) != len(paths):
        raise MechanismError("/parameters", "a path is listed twice")
    if spec.continuation is not None and spec.continuation not in paths:
        raise MechanismError(
            "/continuation", f"'{spec.continuation}' is not one of the swept paths ({', '.join(paths)})"
        )
    analysis = ANALYSES.named(spec.analysis)
    if not analysis.sweepable:
        sweepable = ", ".join(a["name"] for a in ANALYSES.describe() if a["sweepable"])
        raise MechanismError(
            "/analysis", f"the {analysis.name} analysis has no points to sweep (sweepable: {sweepable})"
        )
    return values, shape, paths


class SweepJob:
    name = "sweep"
    paged = True
    Options = SweepOptions
    route, operation_id, request_name = "sweeps", "create_sweep", "SweepRequest"
    title = "Start a sweep job"
    summary = "A job: numeric fields varied over a grid, each point an equilibrium (or a sweepable analysis)."
    description = (
        "Every point is stored as soon as its task finishes; follow the job at /v1/jobs/{id} and "
        "read the points at /v1/jobs/{id}/result (also while it runs)."
    )
    examples = SWEEP_EXAMPLES

    def prepare(self, stored: JSON, limits: Limits) -> Plan:
        spec = read_spec(SweepSpec, stored)
        grid_size(spec.parameters, spec.grid, limits, spec.until is not None)  # before any solve
        mech = compile_request(spec.document, spec.model, spec.overrides, limits)
        newton_options(spec.options)
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
                where = f"/parameters/{k}/values/{i}" if spec.parameters[k].values is not None else f"/parameters/{k}"
                mech.checked_si(path, value, where)
        all_units = output_units(mech)
        wanted = spec.outputs or list(all_units)
        for k, name in enumerate(wanted):
            if name not in all_units:
                raise MechanismError(f"/outputs/{k}", f"unknown output '{name}'")
        kept = len(wanted) + (mech.n_free if spec.continuation is not None else 0)
        check_result_size(int(np.prod(shape)), kept, limits)
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

    def failed(self, point: JSON) -> bool:
        return point.get("status") != "converged"

    def tasks(self, stored: JSON, plan: JSON, finished: Mapping[int, JSON], chunk_size: int) -> list[JSON]:
        spec = read_spec(SweepSpec, stored)
        tasks = []
        lines = _lines(spec, plan)
        if spec.continuation is None:
            todo = [line[0] for line in lines if line[0] not in finished]
            for start in range(0, len(todo), chunk_size):
                tasks.append({"indices": todo[start : start + chunk_size], "guess": None})
        else:
            for number, line in enumerate(lines):
                task = self._next_on_line(line, number, finished, chunk_size)
                if task is not None:
                    tasks.append(task)
        return [self._with_values(t, spec, plan) for t in tasks]

    def follow_up(
        self, stored: JSON, plan: JSON, task: JSON, finished: Mapping[int, JSON], chunk_size: int
    ) -> list[JSON]:
        if task.get("line") is None:
            return []
        spec = read_spec(SweepSpec, stored)
        line = _lines(spec, plan)[task["line"]]
        nxt = self._next_on_line(line, task["line"], finished, chunk_size)
        return [self._with_values(nxt, spec, plan)] if nxt is not None else []

    @staticmethod
    def remainder(task: JSON, finished: Mapping[int, JSON]) -> JSON | None:
        """A load path's chunk: None (follow_up goes on from its last stored point); an
        independent chunk: its unfinished points."""
        return None if task.get("line") is not None else unfinished_part(task, finished)

    @staticmethod
    def _with_values(task: JSON, spec: SweepSpec, plan: Mapping[str, Any]) -> JSON:
        """The task with its points' values (the plan's grid) and the solve time limit."""
        values = [p["values"] for p in plan["parameters"]]
        grid, shape = spec.grid, tuple(plan["shape"])
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

    def run(self, stored: JSON, task: JSON) -> list[tuple[int, JSON]]:
        spec = read_spec(SweepSpec, stored)
        mech = mechanism_of(spec)
        analysis = ANALYSES.named(spec.analysis)
        control = TaskControl(task)
        if task.get("values") is not None:
            at = dict(zip(task["indices"], task["values"]))
        else:  # a task stored before tasks carried their values: the grid again (no until then)
            values, shape = grid_shape(spec.parameters, spec.grid)
            at = {i: point_values(values, shape, spec.grid, i) for i in task["indices"]}
        slots = [mech.parameter_index(p.path) for p in spec.parameters]
        factors = [mech.nd_per_doc(mech.parameters[k].kind) for k in slots]
        names, kinds = mech.graphs.output_names, mech.graphs.output_kinds
        wanted = spec.outputs or list(names)
        columns = [(names.index(n), mech.nd_per_doc(kinds[names.index(n)])) for n in wanted]
        p0 = mech.p()
        zero = np.zeros(mech.n_free)
        z_prev = np.asarray(task["guess"], dtype=float) if task.get("guess") is not None else zero
        along_path = task.get("line") is not None
        points = []
        for index in task["indices"]:
            if control.between_points():  # cancelled or out of time (the rest is dropped), or asked to yield
                break
            options = newton_options(spec.options, control.time_limit(task.get("time_limit")))
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

    def result(self, stored: JSON, plan: JSON, finished: Mapping[int, JSON]) -> JSON:
        spec = read_spec(SweepSpec, stored)
        points = [{"index": i, **{k: v for k, v in d.items() if k != "z"}} for i, d in sorted(finished.items())]
        return {
            "parameters": plan["parameters"],
            "grid": spec.grid,
            "continuation": spec.continuation,
            "output_units": plan["output_units"],
            "residual_unit": plan["force_unit"],
            "residual_moment_unit": plan.get("moment_unit"),
            "analysis": spec.analysis,
            "points": points,
            **({"until": plan["until"]} if plan.get("until") else {}),
        }


def _lines(spec: SweepSpec, plan: Mapping[str, Any]) -> list[list[int]]:
    return load_paths([p.path for p in spec.parameters], spec.grid, spec.continuation, tuple(plan["shape"]))


SWEEP = SweepJob()
