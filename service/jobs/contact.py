"""The contact job: a quasi-static contact path, state after state, each stored as it
finishes (so a path resumed after a restart starts from exactly the stored state).

spec:
  document      the mechanism document (with contacts)
  path          [{path, values} | {path, start, stop, steps}]: the fields that change together
                (default: the document's contacts.path)
  outputs       optional outputs to keep per state (default: every pair's results)
  penetrating_start   approach | refuse (the first state)
  model, options, overrides   as for /v1/solve
"""

from __future__ import annotations

from collections.abc import Mapping

from models import MechanismError
from service.contact.path import (
    default_outputs,
    follow,
    parameters_at,
    path_count,
    path_fields,
    resumed_state,
    state_record,
)
from service.contact.problem import contact_problem
from service.contact.report import penetration_error
from service.contact.solve import ContactOptions, PenetratingStart
from service.costs import Limits, check_grid_size, check_result_size
from service.jobs.base import InOrder, Plan
from service.jobs.control import TaskControl
from service.jobs.sweep import mechanism_of
from service.requests import compile_request, newton_options, under


def path_parameters(spec: dict) -> list[dict]:
    if spec.get("path"):
        return spec["path"]
    contacts = (spec.get("document") or {}).get("contacts") or {}
    if not (contacts.get("path") or {}).get("parameters"):
        raise MechanismError(
            "/path", "a contact path needs fields to change: give path, or contacts.path in the document"
        )
    return contacts["path"]["parameters"]


def wanted_outputs(spec: dict, problem) -> list[str]:
    contacts = (spec.get("document") or {}).get("contacts") or {}
    wanted = spec.get("outputs") or (contacts.get("path") or {}).get("outputs") or default_outputs(problem)
    for k, name in enumerate(wanted):
        if name not in problem.output_names:
            raise MechanismError(f"/outputs/{k}", f"unknown output '{name}'")
    return list(wanted)


class ContactJob(InOrder):
    name = "contact"
    paged = True

    def prepare(self, spec: dict, limits: Limits) -> Plan:
        parameters = path_parameters(spec)
        total = check_grid_size([path_count(parameters)], limits, "/path")
        mech = compile_request(spec["document"], spec.get("model"), spec.get("overrides"), limits)
        newton_options(spec.get("options"))
        problem = contact_problem_of(mech)
        fields = path_fields(mech, parameters)
        outputs = wanted_outputs(spec, problem)
        drawn = 3 * sum(count for _, count in problem.drawn_links) + sum(count for _, count, _ in problem.drawn_jaws)
        per_state = len(outputs) + problem.n_w + problem.n_eq + problem.n_in + 2 * problem.n_pairs
        check_result_size(total, per_state + 2 * (drawn + 73 * problem.n_pairs), limits)
        units = [mech.doc_unit(mech.parameter_kind(p)) for p in fields.pointers]
        meta = {
            "parameters": [
                {"path": p, "unit": u, "values": list(v)} for p, u, v in zip(fields.pointers, units, fields.values)
            ],
            "output_units": {n: mech.doc_unit(problem.output_kinds[problem.output_names.index(n)]) for n in outputs},
            "force_unit": mech.doc_unit("force"),
            "length_unit": mech.doc_unit("length"),
            "solve_time_limit": limits.solve_time_limit,
        }
        return Plan(total, meta)

    def failed(self, point: dict) -> bool:
        return point.get("status") != "converged"

    @staticmethod
    def next_chunk(plan: dict, finished: Mapping[int, dict], chunk_size: int) -> dict | None:
        """The next chunk: from the first unfinished state, after the last converged one."""
        total = len(plan["parameters"][0]["values"])
        position = next((i for i in range(total) if i not in finished), None)
        if position is None:
            return None
        resume = next((i for i in reversed(range(position)) if finished[i]["status"] == "converged"), None)
        return {
            "indices": list(range(position, min(position + chunk_size, total))),
            "resume": resume,
            "resume_state": finished[resume]["state"] if resume is not None else None,
            "time_limit": plan.get("solve_time_limit"),
        }

    def run(self, spec, task):
        mech = mechanism_of(spec)
        problem = contact_problem(mech.structure)
        fields = path_fields(mech, path_parameters(spec))
        outputs = wanted_outputs(spec, problem)
        control = TaskControl(task)
        previous = None
        if task.get("resume") is not None:
            previous = resumed_state(problem, parameters_at(mech, fields, task["resume"]), task["resume_state"])
        time_limit = control.time_limit(task.get("time_limit"))
        options = ContactOptions(
            spec.get("penetrating_start") or "approach", newton_options(spec.get("options"), time_limit).time_limit
        )
        points = []
        try:
            for index, state in follow(mech, problem, fields, task["indices"], previous, options, control.should_stop):
                points.append((index, state_record(mech, problem, state, fields.at(index), outputs)))
        except PenetratingStart as error:
            raise penetration_error(mech, error) from None
        return points

    def result(self, spec, plan, finished):
        points = [{"index": i, **{k: v for k, v in d.items() if k != "state"}} for i, d in sorted(finished.items())]
        return {
            "parameters": plan["parameters"],
            "output_units": plan["output_units"],
            "force_unit": plan["force_unit"],
            "length_unit": plan["length_unit"],
            "points": points,
        }


def contact_problem_of(mech):
    try:
        return contact_problem(mech.structure)
    except MechanismError as exc:
        raise under("/document", exc) from None


CONTACT = ContactJob()
