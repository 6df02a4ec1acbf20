"""The simulate analysis: a time simulation of the mechanism (service.dynamics) by its
document's `simulate` section, with the request's `simulate` fields over it. Answered in one
response, so its steps are bounded (SYNC_STEPS)."""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from pydantic import Field, JsonValue, create_model
from pydantic.fields import FieldInfo

from flexmech.models import Mechanism
from flexmech.models.documents.fields import StrictModel
from flexmech.models.documents.simulation_spec import IMPACT_SCHEMES, SimulateSpec
from flexmech.service.analyses.base import Analysis, AnalysisOptions, AnalysisResult, ReportSize, state_numbers
from flexmech.service.deadline import ends_after, passed
from flexmech.service.dynamics.run import kept_state_numbers, run_simulation, simulation_spec
from flexmech.service.impacts.run import run_impacts
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.reports import plain

SYNC_STEPS = 20_000
SYNC_IMPACT_STEPS = 2_000_000  # a microsecond each: a few seconds of a compiled impact model
SYNC_KEPT = 100_000  # states in one response (about 25 numbers each)
SYNC_IMPACT_BYTES = 192 * 2**20  # the memory one run's states may take in a solver worker


# Where the workbench's form starts a field from (the document's own section, else a drawing's need).
FORM_STARTS: dict[str, dict[str, JsonValue]] = {"shapes": {"form_default": True}}


def _overriding(name: str, info: FieldInfo) -> tuple[Any, FieldInfo]:
    """A field of the simulate section as an override: absent (None) unless given."""
    field = copy.copy(info)
    field.default, field.default_factory = None, None
    field.json_schema_extra = FORM_STARTS.get(name)
    annotation: Any = info.annotation
    return annotation | None, field


_OVERRIDES: dict[str, Any] = {name: _overriding(name, info) for name, info in SimulateSpec.model_fields.items()}
SimulateOverrides = create_model(
    "SimulateOverrides",
    __base__=StrictModel,
    __module__=__name__,
    __doc__="Fields of the document's `simulate` section that override it (the merged section is checked as the "
    "document's is)",
    **_OVERRIDES,
)


class SimulateOptions(AnalysisOptions):
    simulate: SimulateOverrides | None = Field(  # type: ignore[valid-type]
        None,
        description="fields of the document's `simulate` section that override it",
        examples=[{"until": 0.1, "step": 0.001}],
        json_schema_extra={"document_default": "/simulate"},
    )


class SimulateReport(AnalysisResult):
    times: list[float] = Field(default_factory=list, description="the kept times, s")
    outputs: dict[str, list[float | None]] = Field(default_factory=dict, description="per output its kept values")
    output_units: dict[str, str] = Field(default_factory=dict)


REPORT_RESERVE = 3.0  # times the measured cost of making one kept state's records


def _leaving_time_for_the_report(
    mech: Mechanism, spec: SimulateSpec, end: float
) -> tuple[Callable[[], bool], Callable[[float, int], None]]:
    """(stop, progress) for a link simulation under a time limit: the stepping stops early
    enough that the report of its kept states is made before `end` too. Making it costs about
    one outputs evaluation (and one centre-line drawing) per kept state: 6500 states of a
    64-element rod once took 0.8 s after the stepping had used the whole limit, and the server
    replaced the worker (a 503 instead of a time_limit report)."""
    x0, p = np.zeros(mech.graphs.outputs.size1_in(0)), mech.p()  # a state as records() evaluates them
    timed = [mech.graphs.outputs] + ([mech.graphs.shapes] if spec.shapes else [])
    for fn in timed:
        fn(x0, p)  # a first call may set things up: not a kept state's cost
    started = time.perf_counter()
    for fn in timed:
        fn(x0, p)
    per_state = time.perf_counter() - started
    steps = [0]

    def progress(t: float, done: int) -> None:
        steps[0] = done

    def stop() -> bool:
        return passed(end - REPORT_RESERVE * per_state * steps[0] / spec.every)

    return stop, progress


class SimulateAnalysis(Analysis):
    name = "simulate"
    summary = (
        "Motion in time: Newmark or generalized-alpha steps of the links' and bodies' dynamics under loads "
        "and prescribed motions in time; outputs, constraint forces and the energy balance per step; rigid bodies with "
        "contact impacts and friction (event-driven or Moreau-Jean)"
    )

    long = True
    Options = SimulateOptions
    Result = SimulateReport

    def report(self, mech: Mechanism, newton: NewtonOptions, options: SimulateOptions) -> dict:
        given: dict[str, Any] = options.simulate.model_dump(exclude_none=True) if options.simulate is not None else {}
        spec = simulation_spec(mech, given)
        limit = newton.time_limit
        end = ends_after(limit)
        stop = (lambda: passed(end)) if limit else None
        if spec.scheme in IMPACT_SCHEMES:
            _, report = run_impacts(
                mech.document,
                spec,
                stop=stop,
                max_steps=SYNC_IMPACT_STEPS,
                max_kept=SYNC_KEPT,
                max_bytes=SYNC_IMPACT_BYTES,
            )
        else:
            stop, progress = _leaving_time_for_the_report(mech, spec, end) if limit else (None, None)
            _, report = run_simulation(mech, spec, stop=stop, progress=progress, max_steps=SYNC_STEPS)
        if report["status"] == "stopped":
            report["status"] = "time_limit"
            report["message"] += f" (the time limit of {limit:g} s; a simulation job has more time)"
        return plain(report)

    def report_size(self, mech: Mechanism, options: SimulateOptions) -> ReportSize:
        """Per kept state its time, outputs, constraint and motion forces, energies and (with
        shapes) centre lines; link dynamics keep every `every`-th of at most SYNC_STEPS steps, an
        impact run at most its max_points (and the states about each contact's onset and end)."""
        given: dict[str, Any] = options.simulate.model_dump(exclude_none=True) if options.simulate is not None else {}
        spec = simulation_spec(mech, given)
        if spec.until is None:
            return super().report_size(mech, options)  # the run refuses it, naming the field
        if spec.scheme in IMPACT_SCHEMES:  # rigid bodies: their own outputs, a few of each body
            kept = 2 * min(spec.max_points, SYNC_KEPT)
            outputs = len(spec.outputs) if spec.outputs is not None else len(mech.graphs.output_names)
            per_state = 8 + 2 * outputs + mech.n_free
        else:
            steps = SYNC_STEPS if spec.adaptive else min(SYNC_STEPS, math.ceil(spec.until / spec.step))
            kept = steps // spec.every + 2
            per_state = kept_state_numbers(mech, spec)
        return ReportSize(
            kept * per_state + state_numbers(mech),
            f"{kept} kept states x {per_state} numbers",
            "/simulate/every" if not spec.shapes else "/simulate/shapes",
            "keep fewer states (a larger `every`, a shorter `until`)"
            + (" or leave out the shapes (shapes: false)" if spec.shapes else ""),
        )


SIMULATE = SimulateAnalysis()
