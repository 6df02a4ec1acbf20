"""The optimize job: a design problem whose starts are its points.

spec:
  document     the mechanism document (JSON object)
  problem      optional design problem (the document's `optimize` section when absent)
  model, overrides   as for /v1/solve
Each start (0: the document's design; k: a seeded random point in the bounds) is one point,
run by any worker; the result is the best feasible start (the least infeasible if none).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from functools import lru_cache
from typing import Any

import numpy as np
from pydantic import ConfigDict, Field

from flexmech.models import MechanismError
from flexmech.models.documents.document import parse_optimize_spec
from flexmech.models.documents.fields import Name
from flexmech.service.design.optimize import Prepared, StartResult, combine, prepare, run_start
from flexmech.service.design.problem import DesignProblem, design_problem
from flexmech.service.jobs.base import JSON, JobOptions, Plan, StoredJob, read_spec
from flexmech.service.jobs.control import TaskControl
from flexmech.service.requests import Limits, compile_request, under
from flexmech.service.solvers.reports import plain


class OptimizeOptions(JobOptions):
    problem: dict[Name, Any] | None = Field(
        None,
        description="design problem, in the shape of the document's optimize section (checked as it is): design "
        "[{path, lower, upper, scale}], objective {output, case, sense}, constraints [{output, case, lower, upper | "
        "equals}], cases {name: {overrides}}, starts, seed, max_iterations, tolerance (default: the document's "
        "optimize section)",
        json_schema_extra={"document_default": "/optimize"},
    )


class OptimizeJobSpec(StoredJob, OptimizeOptions):
    model_config = ConfigDict(extra="ignore")


EXAMPLES = [
    {"example": "grasper_shape"},
    {
        "example": "grasper_shape",
        "problem": {
            "design": [
                {"path": "/elements/link/length", "lower": 0.0508, "upper": 0.085},
                {"path": "/elements/link/shape/coefficients/0", "lower": 0, "upper": 2},
            ],
            "objective": {"output": "reactions.tip.Fy"},
            "constraints": [{"output": "elements.link.x_end_undeformed", "equals": 0.0508}],
            "starts": 2,
        },
    },
]


def _key(stored: JSON) -> tuple[str, str | None, str, str]:
    """What a design problem is compiled from, as text (the caches' key)."""
    spec = read_spec(OptimizeJobSpec, stored)
    return (
        json.dumps(spec.document, sort_keys=True),
        spec.model,
        json.dumps(spec.overrides or {}, sort_keys=True),
        json.dumps(spec.problem, sort_keys=True),
    )


def problem_of(stored: JSON) -> DesignProblem:
    return _problem(*_key(stored))


@lru_cache(maxsize=8)
def _problem(document_json: str, model: str | None, overrides_json: str, problem_json: str) -> DesignProblem:
    mech = compile_request(json.loads(document_json), model, json.loads(overrides_json))
    given = json.loads(problem_json)
    if given is not None:
        try:
            spec = parse_optimize_spec(given)
        except MechanismError as exc:
            raise under("/problem", exc) from None
        return design_problem(mech, spec, "/problem")
    if mech.document.optimize is None:
        raise MechanismError("/document/optimize", "the document has no optimize section: add one or give 'problem'")
    return design_problem(mech, mech.document.optimize, "/document/optimize")


@lru_cache(maxsize=8)
def _prepared(key: tuple) -> Prepared:
    return prepare(_problem(*key))


def prepared_of(stored: JSON) -> Prepared:
    return _prepared(_key(stored))


def start_from_point(data: dict) -> StartResult:
    fields = {k: v for k, v in data.items() if k in StartResult.__dataclass_fields__}
    for name in ("x", "lam_g", "lam_x"):
        fields[name] = np.asarray(data[name], dtype=float)
    return StartResult(**fields)


class OptimizeJob:
    name = "optimize"
    paged = False  # the result is the best start: it needs every start (at most 64)
    Options = OptimizeOptions
    route, operation_id, request_name = "optimize", "create_optimization", "OptimizeRequest"
    title = "Start an optimization job"
    summary = (
        "A job: a design problem solved as one NLP (design variables and every load case's equilibrium), from one "
        "or more starts."
    )
    description = (
        "Each start is a point of the job, stored when it finishes; the result (at /v1/jobs/{id}/result) is the "
        "best feasible start with its multipliers, iterations and history, or status infeasible with how far each "
        "constraint stays from its bounds."
    )
    examples = EXAMPLES

    def prepare(self, spec: dict, limits: Limits) -> Plan:
        problem = problem_of(spec)
        if len(problem.mechanism.document.elements) > limits.max_elements:
            raise MechanismError("/document/elements", f"the limit is {limits.max_elements} elements")
        return Plan(problem.spec.starts, {"starts": problem.spec.starts})

    def failed(self, point: dict) -> bool:
        """A start that found no optimum (infeasible, off its branch, not converged)."""
        return point.get("status") not in ("optimal", "acceptable")

    def tasks(self, spec, plan, finished, chunk_size):
        todo = [k for k in range(plan["starts"]) if k not in finished]
        return [{"indices": todo[i : i + chunk_size]} for i in range(0, len(todo), chunk_size)]

    def follow_up(self, spec, plan, task, finished, chunk_size):
        return []

    def run(self, spec, task):
        prepared = prepared_of(spec)
        points = []
        control = TaskControl(task)
        for k in task["indices"]:
            if control.between_points():  # cancelled or out of time (the rest is dropped), or asked to yield
                break
            start = run_start(prepared, k, stop=control.stop_or_yield)  # a yield ends a start too
            if control.yielded_midway():  # its worker given to another key: the start runs again, whole
                break
            points.append(
                (k, plain({**start.summary(), "start": k, "x": start.x, "lam_g": start.lam_g, "lam_x": start.lam_x}))
            )
        return points

    def result(self, spec, plan, finished: Mapping[int, dict]):
        problem = problem_of(spec)
        starts = [start_from_point(data) for _, data in sorted(finished.items())]
        outcome = combine(problem, starts, sum(s.seconds for s in starts))
        return plain(outcome.summary())


OPTIMIZE = OptimizeJob()
