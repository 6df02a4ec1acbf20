"""The simulation job: a time simulation stored per time window as it finishes. A window is
a point; it keeps its states (document units) and the exact state it ended in, so that a job
resumed after a kill goes on from the last stored window as if never stopped.

spec:
  document    the mechanism document (its `simulate` section: until, step, scheme, histories)
  simulate    optional fields over the document's section
  model, overrides, options    as for /v1/solve
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from pydantic import ConfigDict

from flexmech.models import MechanismError
from flexmech.models.contact.elastic_pairs import check_link_dynamics
from flexmech.models.documents.simulation_spec import IMPACT_SCHEMES
from flexmech.service.analyses.simulate import SimulateOptions
from flexmech.service.costs import Limits, check_result_size
from flexmech.service.dynamics.histories import read_histories
from flexmech.service.dynamics.integrate import Resume, integrate
from flexmech.service.dynamics.run import (
    MAX_STEPS,
    check_masses,
    check_scheme,
    check_stage_scheme,
    check_steps,
    kept_state_numbers,
    records,
    scheme_of,
    scheme_summary,
    simulated,
    simulation_spec,
    start_shape,
    step_limit,
    tolerance_of,
    units,
    wanted_outputs,
    with_balance,
)
from flexmech.service.dynamics.stepping import WINDOW
from flexmech.service.jobs.base import JSON, InOrder, JobOptions, Plan, StoredJob, read_spec
from flexmech.service.jobs.control import TaskControl
from flexmech.service.jobs.sweep import mechanism_of
from flexmech.service.requests import compile_request, under
from flexmech.service.solvers.reports import output_units


class SimulationOptions(JobOptions, SimulateOptions):
    """The simulate analysis' options (one model: service.analyses.simulate)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class SimulationSpec(StoredJob, SimulationOptions):
    model_config = ConfigDict(extra="ignore")

    def overrides_of_simulate(self) -> dict[str, Any]:
        """The request's fields over the document's simulate section."""
        return self.simulate.model_dump(exclude_none=True) if self.simulate is not None else {}


EXAMPLES = [
    {"example": "spinning_rod_case1", "simulate": {"until": 2.0, "step": 0.01}},
    {"example": "four_bar_dynamics", "simulate": {"until": 0.1}},
    {"example": "spinning_rod_case1", "simulate": {"until": 1e9, "step": 1e-6}},
]

WINDOWS = 100  # a run is stored in about this many windows (points), each a whole number of step windows


class SimulationJob(InOrder):
    name = "simulation"
    paged = True
    Options = SimulationOptions
    route, operation_id, request_name = "simulations", "create_simulation", "SimulationRequest"
    title = "Start a simulation job"
    summary = (
        "A job: a time simulation by the document's `simulate` section (with `simulate` over it), stored per time "
        "window as it runs."
    )
    description = "Every time window is stored as soon as it is integrated; read them at /v1/jobs/{id}/result."
    examples = EXAMPLES

    def prepare(self, stored: JSON, limits: Limits) -> Plan:
        spec = read_spec(SimulationSpec, stored)
        mech = simulated(compile_request(spec.document, spec.model, spec.overrides, limits))
        simulate = simulation_spec(mech, spec.overrides_of_simulate())
        if simulate.scheme in IMPACT_SCHEMES:
            raise MechanismError(
                "/simulate/scheme",
                f"an {simulate.scheme} impact simulation runs in one call of "
                "/v1/solve (analysis simulate: a second of motion takes milliseconds); the impact "
                "study job (/v1/impact-studies) runs many",
            )
        if simulate.accuracy is not None:
            raise MechanismError(
                "/simulate/accuracy",
                "an accuracy target compares whole runs, which a job's stored windows are not: run it by "
                "/v1/solve (analysis simulate) or `flexmech simulate --accuracy`, then start the job with the "
                "elements and step it reports",
            )
        try:
            check_masses(mech)
            check_link_dynamics(mech.document)  # its contact pairs' laws, as a call of /v1/solve checks them
        except MechanismError as exc:
            raise under("/document", exc) from None
        steps = check_steps(simulate, limits.max_simulation_steps)  # adaptive: as many as the first step makes
        check_scheme(mech, simulate)
        histories = read_histories(mech, simulate.histories, simulate.until, "/simulate/histories")
        check_stage_scheme(mech, simulate, histories)
        outputs = wanted_outputs(mech, simulate)
        kept = steps // simulate.every + 2
        check_result_size(kept, kept_state_numbers(mech, simulate), limits, "/simulate/every")
        if simulate.adaptive:
            windows = WINDOWS
            span = simulate.until / windows
        else:
            window = WINDOW * max(1, math.ceil(steps / WINDOWS / WINDOW))  # the stepping's own windows fit
            windows, span = math.ceil(steps / window), window * simulate.step
        meta = {
            "windows": windows,
            "span": span,
            "step": simulate.step,
            "until": simulate.until,
            "max_steps": step_limit(simulate, limits.max_simulation_steps),
            "scheme": scheme_summary(simulate),
            "units": units(mech),
            "output_units": {name: unit for name, unit in output_units(mech).items() if name in outputs},
        }
        return Plan(windows, meta)

    def failed(self, point: dict) -> bool:
        return point.get("status") != "finished"

    @staticmethod
    def next_chunk(plan: dict, finished: Mapping[int, dict], chunk_size: int) -> dict | None:
        """The next windows, from the end of the last stored one; none after a failed one."""
        position = next((i for i in range(plan["windows"]) if i not in finished), None)
        if position is None or (position > 0 and finished[position - 1].get("status") != "finished"):
            return None
        resume = finished[position - 1]["resume"] if position > 0 else None
        size = 1 if position == 0 else chunk_size  # the first window alone: progress shows from it
        return {
            "indices": list(range(position, min(position + size, plan["windows"]))),
            "resume": resume,
            "span": plan["span"],
            "max_steps": plan.get("max_steps"),
        }

    def run(self, stored: JSON, task: JSON) -> list[tuple[int, JSON]]:
        spec = read_spec(SimulationSpec, stored)
        mech = simulated(mechanism_of(spec))
        simulate = simulation_spec(mech, spec.overrides_of_simulate())
        histories = read_histories(mech, simulate.histories, simulate.until, "/simulate/histories")
        control = TaskControl(task)
        p, scheme = mech.p(), scheme_of(simulate)
        at = Resume.from_json(task["resume"]) if task.get("resume") is not None else None
        x0 = start_shape(mech, simulate, histories)[0] if at is None else None
        points = []
        for index in task["indices"]:
            if control.between_points():  # cancelled or out of time, or asked to yield: the next window waits
                break
            end = min((index + 1) * task["span"], simulate.until)
            started = 0.0 if at is None else at.time
            history = integrate(
                mech.structure,
                p,
                x0,
                None if x0 is None else 0 * x0,
                end,
                simulate.step,
                scheme,
                damping=simulate.damping,
                every=simulate.every,
                stop=control.should_stop,
                histories=histories,
                resume=at,
                adaptive=tolerance_of(simulate, task.get("max_steps") or MAX_STEPS),
            )
            points.append(
                (
                    index,
                    {
                        "status": history.status,
                        "message": history.message,
                        "t_start": started,
                        "t_end": history.resume.time,
                        **records(mech, simulate, history, histories),
                        "resume": history.resume.to_json(),
                    },
                )
            )
            if history.status != "finished":
                break
            at, x0 = history.resume, None
        return points

    def result(self, stored: JSON, plan: JSON, finished: Mapping[int, JSON]) -> JSON:
        windows = [finished[i] for i in sorted(finished)]
        joined = {
            "times": [],
            "outputs": {},
            "constraint_forces": {},
            "motion_forces": {},
            "energies": {
                "kinetic": [],
                "potential": [],
                "input_work": [],
                "damping_work": [],
                "friction_work": [],
                "contact_damping_work": [],
            },
        }
        varying: dict = {"values": {}, "units": {}}
        for window in windows:
            joined["times"] += window["times"]
            for group in ("outputs", "constraint_forces", "motion_forces", "energies"):
                for name, values in window[group].items():
                    joined[group].setdefault(name, []).extend(values)
            if "shapes" in window:
                joined.setdefault("shapes", []).extend(window["shapes"])
            for name, values in window.get("varying", {}).get("values", {}).items():  # none in windows stored before it
                varying["values"].setdefault(name, []).extend(values)
            varying["units"].update(window.get("varying", {}).get("units", {}))
        energies, error = with_balance(joined.pop("energies"))
        last = windows[-1] if windows else None
        if last is None:
            status = "running"
        elif last["status"] != "finished" or len(windows) == plan["windows"]:
            status = last["status"]
        else:
            status = "running"
        return {
            **plan,
            "status": status,
            "message": last["message"] if last else "",
            "time_reached": last["t_end"] if last else 0.0,
            "windows_stored": len(windows),
            "steps": last.get("steps") if last else 0,  # a window's count runs on from the run's start
            **joined,
            "energies": energies,
            "energy_balance_error": error,
            "output_units": plan.get("output_units", {}),
            "series_units": {name: unit for window in windows for name, unit in window.get("series_units", {}).items()},
            "varying": varying,
        }


SIMULATION = SimulationJob()
