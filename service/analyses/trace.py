"""The trace analysis: the equilibrium path of a numeric field (usually a load) through limit
points, by pseudo-arc-length continuation (service.solvers.continuation.trace_path), as `flexmech
trace` follows it.

The request's `trace` = {path, stop, step, max_points} (document units of the field) follows
`path` from its value in the document (overrides applied) until it passes `stop`. Without
it, the document's sweep section: `path` from sweep.start to sweep.stop, the first step one
of its steps, |stop - start| / steps.

The report (document units) has the path's points (the field's `value`, `outputs`, `stable`,
`rising`, the body stiffness' `eigenvalues`), its `limit_points`, and for plotting the same
numbers as columns: `values` (the field per point) and `outputs` ({output: [value per point]}),
and `frames`: the deformed states to animate (at most MAX_FRAMES, evenly spread).
The work is bounded by max_points (at most MAX_POINTS) and by the time limit of the options:
a path stopped by it is status "time_limit" with its points so far.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import Field

from flexmech.models import Mechanism, MechanismError
from flexmech.models.documents.fields import MAX_POINTER_CHARS
from flexmech.models.units import quantity_to_si
from flexmech.service.analyses.base import (
    Analysis,
    AnalysisOptions,
    AnalysisResult,
    ReportSize,
    drawn_numbers,
    state_numbers,
)
from flexmech.service.deadline import ends_after, passed
from flexmech.service.drawings.drawing import state_frame
from flexmech.service.requests import under
from flexmech.service.solvers.continuation import PathResult, trace_path
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.reports import output_units, plain

DEFAULT_POINTS = 400
MAX_FRAMES = 400  # states of the path drawn for the animation
MAX_POINTS = 100_000

# trace_path's statuses as the statuses of a solve response: the path reached its stop, or it
# did not (no start, a corrector that failed, or max_points first), or the time limit stopped
# it. The original is the report's path_status.
STATUSES = {
    "completed": "converged",
    "not_converged": "not_converged",
    "max_points": "not_converged",
    "stopped": "time_limit",
}

ASK = "give trace {path, stop, step} (on the command line: flexmech trace DOC --path --stop --step)"


class TraceIn(AnalysisOptions):
    """Follow the equilibrium path of numeric field `path` from its value in the document until
    it passes `stop`, through limit points (pseudo-arc-length continuation)."""

    path: str = Field(
        pattern=r"^/",
        max_length=MAX_POINTER_CHARS,
        description="JSON pointer of the numeric field followed",
        examples=["/loads/P/force/1"],
    )
    stop: float = Field(description="the field's last value, document units of the field")
    step: float = Field(gt=0, description="the first arc-length step, document units of the field")
    max_points: int = Field(DEFAULT_POINTS, ge=2, le=MAX_POINTS, description="points of the path at most")


class TraceOptions(AnalysisOptions):
    trace: TraceIn | None = Field(None, description="the path followed (default: the document's sweep section)")


class TraceReport(AnalysisResult):
    path: str | None = None
    unit: str | None = None
    values: list[float | None] = Field(default_factory=list, description="the field's value per point")
    limit_points: list[dict] = Field(default_factory=list)


@dataclass(frozen=True)
class TraceSpec:
    path: str
    stop: float  # document units of the field
    step: float  # first arc-length step, document units of the field
    max_points: int
    start: float | None = None  # from the sweep section: the field's first value; None: the document's
    source: str = "request"  # request | sweep


def _field_checked(mech: Mechanism, path: Any, pointer: str) -> str:
    if not isinstance(path, str) or not path.startswith("/"):
        raise MechanismError(pointer, f"expected a JSON pointer of a numeric field, got {path!r}")
    try:
        mech.parameter_index(path)
    except MechanismError as exc:
        raise MechanismError(pointer, exc.problem) from None
    return path


def requested_spec(mech: Mechanism, given: TraceIn) -> TraceSpec:
    """The request's trace, its field checked against the mechanism."""
    return TraceSpec(_field_checked(mech, given.path, "/trace/path"), given.stop, given.step, given.max_points)


def sweep_spec(mech: Mechanism) -> TraceSpec:
    """The document's sweep section as a trace: its path from start to stop, steps long."""
    sweep = mech.document.sweep
    if sweep is None or sweep.stop is None:
        why = "no sweep section" if sweep is None else "a sweep section without a stop"
        raise MechanismError("/trace", f"the document has {why} to trace by default: {ASK}")
    path = _field_checked(mech, sweep.path, "/document/sweep/path")
    kind = mech.parameter_kind(path)
    unit = mech.doc_unit(kind)
    start, stop = (
        quantity_to_si(getattr(sweep, name), kind, unit, f"/document/sweep/{name}") / mech.doc_factor(kind)
        for name in ("start", "stop")
    )
    if start == stop:
        raise MechanismError("/trace", f"the document's sweep starts and stops at {start:g} {unit}: {ASK}")
    return TraceSpec(path, stop, abs(stop - start) / sweep.steps, DEFAULT_POINTS, start, "sweep")


def trace_report(mech: Mechanism, options: NewtonOptions, given: TraceIn | None = None) -> dict:
    """Follow the path (the request's trace, else the document's sweep section) and report it;
    errors name the request's field (/trace/..., /document/...)."""
    spec = sweep_spec(mech) if given is None else requested_spec(mech, given)
    if spec.start is not None:
        try:
            mech = mech.with_values({spec.path: spec.start})
        except MechanismError as exc:
            raise MechanismError("/document/sweep/start", exc.problem) from None
    try:
        end = ends_after(options.time_limit)
        result = trace_path(
            mech,
            spec.path,
            spec.stop,
            spec.step,
            spec.max_points,
            options,
            should_stop=(lambda: passed(end)) if options.time_limit else None,
        )
    except MechanismError as exc:
        if exc.pointer in ("/step", "/stop"):
            where = "/trace" if spec.source == "request" else "/document/sweep"
            raise MechanismError(where + exc.pointer, exc.problem) from None
        raise under("/document", exc) from None
    units = output_units(mech)
    body = result.to_dict()
    return plain(
        {
            "analysis": "trace",
            "name": mech.document.name,
            "status": STATUSES.get(result.status, "not_converged"),
            "path_status": result.status,
            "message": result.message,
            "seconds": result.seconds,
            "path": result.path,
            "unit": result.unit,
            "source": spec.source,
            "start": mech.value(spec.path),
            "stop": spec.stop,
            "step": spec.step,
            "max_points": spec.max_points,
            "points": body["points"],
            "limit_points": body["limit_points"],
            "values": [p.value for p in result.points],
            "outputs": {name: [p.outputs.get(name) for p in result.points] for name in units},
            "output_units": units,
            "frames": path_frames(mech, result),
        }
    )


def path_frames(mech: Mechanism, result: PathResult) -> list[dict]:
    """The path's states to animate (service.drawings.drawing.state_frame), at most MAX_FRAMES of them
    evenly spread; each with its index among the points and the field's value."""
    points = result.points
    chosen = sorted(set(np.linspace(0, len(points) - 1, min(len(points), MAX_FRAMES)).round().astype(int).tolist()))
    frames = []
    for index in chosen:
        at = mech.with_values({result.path: points[index].value})
        frames.append(
            {
                "point": index,
                "value": points[index].value,
                **state_frame(at, points[index].z, at.p(), points[index].outputs),
            }
        )
    return frames


class TraceAnalysis(Analysis):
    name = "trace"
    summary = (
        "The equilibrium path of a load (any numeric field) through limit points by arc-length continuation, "
        "with each point's stability and the limit loads located exactly"
    )

    long = True
    Options = TraceOptions
    Result = TraceReport

    def report(self, mech: Mechanism, newton: NewtonOptions, options: TraceOptions) -> dict:
        return trace_report(mech, newton, options.trace)

    def report_size(self, mech: Mechanism, options: TraceOptions) -> ReportSize:
        """Up to max_points points, each with every output by name and as a column, and the body
        stiffness' eigenvalues; up to MAX_FRAMES drawn states."""
        points = options.trace.max_points if options.trace is not None else DEFAULT_POINTS
        per_point = 4 + 3 * len(mech.graphs.output_names) + mech.n_body_coordinates
        frames = min(points, MAX_FRAMES) * drawn_numbers(mech)
        return ReportSize(
            points * per_point + frames + state_numbers(mech),
            f"{points} points x {per_point} numbers, {min(points, MAX_FRAMES)} drawn states",
            "/trace/max_points",
            "allow fewer points (max_points) or take longer steps",
        )


TRACE = TraceAnalysis()
