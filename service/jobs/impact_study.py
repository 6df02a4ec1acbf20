"""The impact study job: seed 004's parametric study (service.impacts.study) run on the
pool or Dask, one point per run: point 0 is the nominal run, then each field moved by +step
and by -step. Points are independent, so they run in any order and in parallel.

spec:
  document    the mechanism document (its `contacts` and `simulate` sections)
  simulate    optional fields over the document's `simulate`
  study       {fields: [{path, step}], tolerance (default 0.05 of each quantity's nominal range)}
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from pydantic import BaseModel, ConfigDict, Field

from flexmech.models import MechanismError
from flexmech.models.documents.fields import MAX_POINTER_CHARS
from flexmech.models.documents.simulation_spec import IMPACT_SCHEMES
from flexmech.service.analyses.simulate import SimulateOverrides
from flexmech.service.costs import Limits, check_grid_size
from flexmech.service.dynamics.run import simulation_spec
from flexmech.service.impacts.run import check_cost, check_memory, model_of
from flexmech.service.impacts.study import legacy_influence, study_fields, study_point, with_overrides
from flexmech.service.jobs.base import JSON, JobOptions, Plan, StoredJob, read_spec
from flexmech.service.jobs.control import TaskControl
from flexmech.service.requests import compile_request

DEFAULT_TOLERANCE = 0.05
RUN_BYTES = 192 * 2**20  # the memory one run's states may take (a task holds the nominal run's and one other)


class StudyField(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    path: str = Field(
        pattern=r"^/", max_length=MAX_POINTER_CHARS, description="a number of the document, by JSON pointer"
    )
    step: float = Field(description="it moves by +step and by -step, in the document's units")


class ImpactStudy(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    fields: list[StudyField] = Field(min_length=1, max_length=64, description="the numbers varied, one at a time")
    tolerance: float = Field(
        DEFAULT_TOLERANCE,
        gt=0,
        lt=1,
        description="a run departs from the nominal one when a quantity differs by more than this fraction of its "
        "nominal range",
    )


class ImpactStudyOptions(JobOptions):
    simulate: SimulateOverrides | None = Field(  # type: ignore[valid-type]
        None,
        description="fields of the document's `simulate` section over it",
        json_schema_extra={"document_default": "/simulate"},
    )
    study: ImpactStudy = Field(description="the fields varied and the departure tolerance")


class ImpactStudySpec(StoredJob, ImpactStudyOptions):
    model_config = ConfigDict(extra="ignore")

    def simulate_given(self) -> dict[str, Any]:
        """The request's fields over the document's simulate section."""
        return self.simulate.model_dump(exclude_none=True) if self.simulate is not None else {}  # type: ignore[attr-defined]


EXAMPLES = [
    {
        "example": "csfh",
        "simulate": {"until": 0.3},
        "study": {
            "fields": [
                {"path": "/contacts/sites/pin/radius", "step": 0.001},
                {"path": "/bodies/hinge/mass", "step": 0.1},
            ]
        },
    },
]


def _document(spec: ImpactStudySpec) -> dict:
    return with_overrides(spec.document, spec.overrides)


def _runs(spec: ImpactStudySpec) -> list[tuple[str | None, float]]:
    fields = study_fields(_document(spec), spec.study.fields)
    runs: list[tuple[str | None, float]] = [(None, 0.0)]
    for pointer, step in fields:
        runs += [(pointer, step), (pointer, -step)]
    return runs


class ImpactStudyJob:
    name = "impact_study"
    paged = False
    Options = ImpactStudyOptions
    route, operation_id, request_name = "impact-studies", "create_impact_study", "ImpactStudyRequest"
    title = "Start a parametric study of an impact simulation"
    summary = "A job: seed 004's parametric study of an impact simulation, one field at a time."
    description = "Each run is stored as it finishes; the result ranks the fields by how early they change the motion."
    examples = EXAMPLES

    def prepare(self, stored: JSON, limits: Limits) -> Plan:
        spec = read_spec(ImpactStudySpec, stored)
        mech = compile_request(spec.document, spec.model, spec.overrides, limits)
        simulate = simulation_spec(mech, spec.simulate_given())
        if simulate.scheme not in IMPACT_SCHEMES:
            raise MechanismError(
                "/simulate/scheme",
                f"an impact study runs an impact scheme ({', '.join(IMPACT_SCHEMES)}), not {simulate.scheme}",
            )
        tolerance = spec.study.tolerance
        runs = _runs(spec)
        check_grid_size([len(runs)], limits, "/study/fields")
        check_cost(simulate, limits.max_simulation_steps)
        model = model_of(mech.document, simulate)
        check_memory(model, simulate, RUN_BYTES)
        return Plan(
            len(runs),
            {
                "runs": [{"path": p, "change": c} for p, c in runs],
                "until": simulate.until,
                "tolerance": tolerance,
                "scheme": simulate.scheme,
                "max_steps": limits.max_simulation_steps,
                "field_units": {path: model.book.units.get(path, ("", 1.0))[0] for path, _ in runs if path is not None},
                "force_unit": mech.doc_unit("force"),
            },
        )

    def tasks(self, spec, plan, finished, chunk_size):
        todo = [k for k in range(len(plan["runs"])) if k not in finished]
        return [
            {"indices": todo[i : i + chunk_size], "max_steps": plan.get("max_steps")}
            for i in range(0, len(todo), chunk_size)
        ]

    def follow_up(self, spec, plan, task, finished, chunk_size):
        return []

    def run(self, stored: JSON, task: JSON) -> list[tuple[int, JSON]]:
        spec = read_spec(ImpactStudySpec, stored)
        runs, control = _runs(spec), TaskControl(task)
        tolerance = spec.study.tolerance
        points = []
        for index in task["indices"]:
            if control.between_points():  # cancelled or out of time, or asked to yield its worker
                break
            pointer, change = runs[index]
            run = study_point(
                _document(spec),
                spec.simulate_given(),
                pointer,
                change,
                tolerance,
                control.stop_or_yield,  # asked to yield, a run ends too: it runs again, whole
                task.get("max_steps", 2_000_000),
            )
            if run["status"] == "stopped":  # cancelled, out of time or yielding: not stored, so it runs again
                break
            points.append((index, {"path": pointer, "change": change, **run}))
        return points

    def failed(self, point: dict) -> bool:
        return point.get("status") != "finished"

    def result(self, stored: JSON, plan: JSON, finished: Mapping[int, JSON]) -> JSON:
        nominal = finished.get(0)
        fields: dict[str, dict] = {}
        if nominal is not None:
            for index, point in sorted(finished.items()):
                if index == 0:
                    continue
                entry = fields.setdefault(point["path"], {})
                side = "+" if point["change"] > 0 else "-"
                influence = point.get("influence")
                if influence is None:  # a point stored by an earlier version: sampled series
                    influence = (
                        legacy_influence(nominal, point, plan["until"], plan["tolerance"])
                        if "series" in nominal and "series" in point
                        else {}
                    )
                entry[side] = {
                    "change": point["change"],
                    "change_unit": plan.get("field_units", {}).get(point["path"], ""),
                    "status": point["status"],
                    "impacts": point["impacts"],
                    "contacts": point.get("contacts"),
                    "influence": influence,
                }
        status = "running" if len(finished) < len(plan["runs"]) else "finished"
        return {
            "status": status,
            "until": plan["until"],
            "tolerance": plan["tolerance"],
            "scheme": plan["scheme"],
            "nominal": None
            if nominal is None
            else {"impacts": nominal["impacts"], "seconds": nominal["seconds"], "contacts": nominal.get("contacts")},
            "fields": fields,
            "ranking": _ranking(fields),
            # by a field's last name: departures and times in s; rms and max relative to the nominal
            # range (a field's change is in its change_unit)
            "units": {
                "impacts": "1",
                "contacts": "1",
                "first_contact": "s",
                "first_separation": "s",
                "peak_time": "s",
                "peak_force": plan.get("force_unit", ""),
                "until": "s",
                "seconds": "s",
                "departure": "s",
                "earliest_departure": "s",
                "tolerance": "1",
                "rms": "1",
                "largest_rms": "1",
                "max": "1",
            },
        }


def _ranking(fields: dict) -> list[dict]:
    """Fields by their earliest departure (then largest rms): the most influential first."""
    rows = []
    for pointer, sides in fields.items():
        departures = [
            v["departure"] for side in sides.values() for v in side["influence"].values() if v["departure"] is not None
        ]
        rms = max((v["rms"] for side in sides.values() for v in side["influence"].values()), default=0.0)
        rows.append(
            {"path": pointer, "earliest_departure": min(departures) if departures else None, "largest_rms": rms}
        )
    return sorted(
        rows, key=lambda r: (r["earliest_departure"] is None, r["earliest_departure"] or 0.0, -r["largest_rms"])
    )


IMPACT_STUDY = ImpactStudyJob()
