"""The analysis job: one analysis of the registry (the body of /v1/solve, at POST
/v1/analysis-jobs), run by a job worker and its report stored as the job's one point, for
reports too large or runs too long to answer in one response (a frequency response of many
points and outputs, a long trace). The report is bounded by what a job stores
(FLEXMECH_MAX_RESULT_VALUES), counted before anything runs (Analysis.report_size).

spec:
  document, model, overrides, options   as for /v1/solve
  analysis                               the analysis' name
  settings                               its own fields, as /v1/solve takes them beside `analysis`
The result (GET /v1/jobs/{id}/result) is {"status", "report"}: the analysis' report, as /v1/solve
would answer it, once stored.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from pydantic import ConfigDict, Field

from flexmech.service.analyses import ANALYSES, AnalysisRequest
from flexmech.service.costs import Limits, check_report_size
from flexmech.service.deadline import stop_scope
from flexmech.service.jobs.base import JSON, JobOptions, Plan, StoredJob, read_spec
from flexmech.service.jobs.control import TaskControl
from flexmech.service.jobs.sweep import mechanism_of
from flexmech.service.requests import compile_request, newton_options


class AnalysisJobOptions(JobOptions):
    """How an analysis job is asked: as /v1/solve is (its `analysis` and the analysis' own fields
    beside it); stored with those fields under `settings`."""

    model_config = ConfigDict(extra="allow")

    analysis: str = Field(min_length=1, max_length=64, description="an analysis of GET /v1/analyses")


class AnalysisJobSpec(StoredJob):
    model_config = ConfigDict(extra="ignore")

    analysis: str
    settings: dict[str, Any] = Field(default_factory=dict)


EXAMPLES = [
    {
        "example": "gripper_modes",
        "analysis": "frequency_response",
        "input": "/loads/actuation/force/1",
        "outputs": ["end_effector.x"],
        "points": 20000,
    }
]


class AnalysisJob:
    name = "analysis"
    paged = False
    Options = AnalysisJobOptions
    # its route takes the body of /v1/solve (the union over the analyses): api.routers.solve makes it
    own_route = True
    route, operation_id, request_name = "analysis-jobs", "create_analysis_job", "AnalysisJobRequest"
    title = "Start one analysis as a job: its report stored, for reports too large to answer at once"
    summary = "A job: one analysis of /v1/solve (the same body), its report stored when it ends."
    description = (
        "The body is /v1/solve's. The analysis runs in a job worker within the job time limit; its report "
        "(at /v1/jobs/{id}/result, under `report`) is bounded by what a job stores, not by the response limit."
    )
    examples = EXAMPLES

    def prepare(self, stored: JSON, limits: Limits) -> Plan:
        spec = read_spec(AnalysisJobSpec, stored)
        analysis = ANALYSES.named(spec.analysis)
        options = analysis.options_of(spec.settings)
        newton_options(spec.options)
        mech = compile_request(spec.document, spec.model, spec.overrides, limits)
        size = analysis.report_size(mech, options)
        check_report_size(size, limits, answered=False)
        return Plan(1, {"analysis": analysis.name, "numbers": size.numbers})

    def tasks(self, spec: JSON, plan: JSON, finished: Mapping[int, JSON], chunk_size: int) -> list[JSON]:
        return [] if 0 in finished else [{"indices": [0]}]

    def follow_up(
        self, spec: JSON, plan: JSON, task: JSON, finished: Mapping[int, JSON], chunk_size: int
    ) -> list[JSON]:
        return []

    def run(self, stored: JSON, task: JSON) -> list[tuple[int, JSON]]:
        control = TaskControl(task)
        if control.between_points():  # cancelled, or asked to yield before it began: it runs later
            return []
        spec = read_spec(AnalysisJobSpec, stored)
        analysis = ANALYSES.named(spec.analysis)
        newton = newton_options(spec.options, control.time_limit(None))
        # Asked to yield while it runs, it ends like a cancelled one and runs again later, whole.
        with stop_scope(control.stop_or_yield):
            report = analysis.run(mechanism_of(spec), AnalysisRequest(newton, spec.settings))
        return [] if control.interrupted or control.should_stop() else [(0, report)]  # cut short: not stored

    def failed(self, point: JSON) -> bool:
        return point.get("status") not in ("converged", "finished")

    def result(self, stored: JSON, plan: JSON, finished: Mapping[int, JSON]) -> JSON:
        report = finished.get(0)
        return {"status": "pending" if report is None else report.get("status"), "report": report}


ANALYSIS_JOB = AnalysisJob()
