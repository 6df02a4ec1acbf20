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
from typing import Literal

from pydantic import ConfigDict, Field

from flexmech.models import Mechanism, MechanismError
from flexmech.models.contact.schema import PathParameter
from flexmech.models.documents.fields import OutputName
from flexmech.service.contact.path import (
    default_outputs,
    follow,
    parameters_at,
    path_count,
    path_fields,
    resumed_state,
    state_record,
)
from flexmech.service.contact.problem import contact_problem
from flexmech.service.contact.report import penetration_error
from flexmech.service.contact.solve import ContactOptions, PenetratingStart
from flexmech.service.costs import Limits, check_grid_size, check_result_size
from flexmech.service.jobs.base import JSON, InOrder, JobOptions, Plan, StoredJob, read_spec
from flexmech.service.jobs.control import TaskControl
from flexmech.service.jobs.sweep import mechanism_of
from flexmech.service.jobs.sweep_options import SweepParameter
from flexmech.service.requests import compile_request, newton_options, under


class ContactPathOptions(JobOptions):
    path: list[SweepParameter] | None = Field(
        None,
        min_length=1,
        max_length=8,
        description="fields that change together along the path",
        json_schema_extra={"document_default": "/contacts/path/parameters/0"},
    )
    outputs: list[OutputName] | None = Field(
        None, min_length=1, max_length=256, description="outputs kept per state (default: every pair's results)"
    )
    penetrating_start: Literal["approach", "refuse"] = Field(
        "approach", description="an object inside a site at the first state is approached from outside, or refused"
    )


class ContactPathSpec(StoredJob, ContactPathOptions):
    model_config = ConfigDict(extra="ignore")


EXAMPLES = [
    {"example": "gripper_jaw_contact"},
    {
        "example": "gripper_jaw_contact",
        "outputs": ["contacts.insertion.force_x"],
        "path": [{"path": "/contacts/objects/fixture/centre/0", "start": 78, "stop": 50, "steps": 28}],
    },
    {
        "example": "gripper_jaw_contact",
        "path": [{"path": "/contacts/objects/fixture/centre/0", "start": 78, "stop": 50, "steps": 10**12}],
    },
]


def path_parameters(spec: ContactPathSpec, mech: Mechanism) -> list[SweepParameter] | list[PathParameter]:
    """The request's path, else the document's contacts.path."""
    if spec.path:
        return spec.path
    declared = mech.document.contacts.path if mech.document.contacts is not None else None
    if declared is None:
        raise MechanismError(
            "/path", "a contact path needs fields to change: give path, or contacts.path in the document"
        )
    return declared.parameters


def wanted_outputs(spec: ContactPathSpec, mech: Mechanism, problem) -> list[str]:
    declared = mech.document.contacts.path if mech.document.contacts is not None else None
    wanted = spec.outputs or (declared.outputs if declared is not None else None) or default_outputs(problem)
    for k, name in enumerate(wanted):
        if name not in problem.output_names:
            raise MechanismError(f"/outputs/{k}", f"unknown output '{name}'")
    return list(wanted)


class ContactJob(InOrder):
    name = "contact"
    paged = True
    Options = ContactPathOptions
    route, operation_id, request_name = "contacts", "create_contact_path", "ContactPathRequest"
    title = "Start a contact path job"
    summary = (
        "A job: a quasi-static contact path (fields changing together, state after state, each from the one "
        "before); without `path`, the document's contacts.path."
    )
    description = "Every state is stored as soon as it is solved; read them at /v1/jobs/{id}/result."
    examples = EXAMPLES

    def prepare(self, stored: JSON, limits: Limits) -> Plan:
        spec = read_spec(ContactPathSpec, stored)
        if spec.path:  # the request's own path is counted before the document is compiled
            check_grid_size([path_count(spec.path)], limits, "/path")
        mech = compile_request(spec.document, spec.model, spec.overrides, limits)
        parameters = path_parameters(spec, mech)
        total = check_grid_size([path_count(parameters)], limits, "/path")
        newton_options(spec.options)
        problem = contact_problem_of(mech)
        fields = path_fields(mech, parameters)
        outputs = wanted_outputs(spec, mech, problem)
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

    def failed(self, point: JSON) -> bool:
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

    def run(self, stored: JSON, task: JSON) -> list[tuple[int, JSON]]:
        spec = read_spec(ContactPathSpec, stored)
        mech = mechanism_of(spec)
        problem = contact_problem(mech.structure)
        fields = path_fields(mech, path_parameters(spec, mech))
        outputs = wanted_outputs(spec, mech, problem)
        control = TaskControl(task)
        previous = None
        if task.get("resume") is not None:
            previous = resumed_state(problem, parameters_at(mech, fields, task["resume"]), task["resume_state"])
        time_limit = control.time_limit(task.get("time_limit"))
        options = ContactOptions(spec.penetrating_start, newton_options(spec.options, time_limit).time_limit)
        points = []
        try:
            for index, state in follow(mech, problem, fields, task["indices"], previous, options, control.should_stop):
                points.append((index, state_record(mech, problem, state, fields.at(index), outputs)))
                if control.should_yield():  # another key's job waits: the path goes on from here later
                    break
        except PenetratingStart as error:
            raise penetration_error(mech, error) from None
        return points

    def result(self, stored: JSON, plan: JSON, finished: Mapping[int, JSON]) -> JSON:
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
