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

from models import MechanismError
from models.simulation_spec import IMPACT_SCHEMES
from service.costs import Limits, check_grid_size
from service.dynamics.run import simulation_spec
from service.impacts.run import check_cost, check_memory, model_of
from service.impacts.study import legacy_influence, study_fields, study_point, with_overrides
from service.jobs.base import Plan
from service.jobs.control import TaskControl
from service.requests import compile_request

DEFAULT_TOLERANCE = 0.05
RUN_BYTES = 192 * 2**20  # the memory one run's states may take (a task holds the nominal run's and one other)


def _document(spec: dict) -> dict:
    return with_overrides(spec["document"], spec.get("overrides"))


def _runs(spec: dict) -> list[tuple[str | None, float]]:
    fields = study_fields(_document(spec), (spec.get("study") or {}).get("fields") or [])
    runs: list[tuple[str | None, float]] = [(None, 0.0)]
    for pointer, step in fields:
        runs += [(pointer, step), (pointer, -step)]
    return runs


class ImpactStudyJob:
    name = "impact_study"
    paged = False

    def prepare(self, spec: dict, limits: Limits) -> Plan:
        mech = compile_request(spec["document"], spec.get("model"), spec.get("overrides"), limits)
        simulate = simulation_spec(mech, spec.get("simulate"))
        if simulate.scheme not in IMPACT_SCHEMES:
            raise MechanismError(
                "/simulate/scheme",
                f"an impact study runs an impact scheme ({', '.join(IMPACT_SCHEMES)}), not {simulate.scheme}",
            )
        tolerance = (spec.get("study") or {}).get("tolerance", DEFAULT_TOLERANCE)
        if not isinstance(tolerance, (int, float)) or not 0 < tolerance < 1:
            raise MechanismError(
                "/study/tolerance",
                "give the departure tolerance as a fraction in (0, 1) of each quantity's nominal range",
            )
        runs = _runs(spec)
        check_grid_size([len(runs)], limits, "/study/fields")
        check_cost(simulate, limits.max_simulation_steps)
        check_memory(model_of(mech.document, simulate), simulate, RUN_BYTES)
        return Plan(
            len(runs),
            {
                "runs": [{"path": p, "change": c} for p, c in runs],
                "until": simulate.until,
                "tolerance": tolerance,
                "scheme": simulate.scheme,
                "max_steps": limits.max_simulation_steps,
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

    def run(self, spec, task):
        runs, control = _runs(spec), TaskControl(task)
        tolerance = (spec.get("study") or {}).get("tolerance", DEFAULT_TOLERANCE)
        points = []
        for index in task["indices"]:
            if control.should_stop():
                break
            pointer, change = runs[index]
            run = study_point(
                _document(spec),
                spec.get("simulate"),
                pointer,
                change,
                tolerance,
                control.should_stop,
                task.get("max_steps", 2_000_000),
            )
            if run["status"] == "stopped":  # cancelled or out of time: not stored, so a restart runs it again
                break
            points.append((index, {"path": pointer, "change": change, **run}))
        return points

    def failed(self, point: dict) -> bool:
        return point.get("status") != "finished"

    def result(self, spec: dict, plan: dict, finished: Mapping[int, dict]) -> dict:
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
