"""What a kind of job must say.

A job is a spec (a JSON object kept in the store) whose work splits into points, each
persisted when it finishes. A kind says:
  prepare(spec, limits) -> Plan      on the server, before the job exists: validate the spec
                                     (MechanismError naming the field) and count its points
  tasks(spec, plan, finished)        the tasks that can run now, given the stored points
                                     (on a fresh job, finished is empty; after a restart, not)
  follow_up(spec, plan, task, finished)  tasks unblocked once `task`'s points are stored
  run(spec, task)                    in a worker process: [(index, point data)]
  failed(point)                      whether a stored point counts as failed (progress.failed_points)
  result(spec, plan, finished)       the job's result from its points (a page of them, if paged)
  archive(spec, plan, finished)      optional: (file name, .tar.gz bytes) of a result that is files
                                     (None until stored), served at GET /v1/jobs/{id}/archive
Tasks and point data are JSON-able dicts, so they travel to process pools and Dask workers
and are stored as they are. The runner and the store know nothing else about a kind.

A kind also says how it is asked for: its `Options` (a pydantic model of its request's own
fields, beside the common ones of StoredJob) and its route; the HTTP route, its OpenAPI
schema, the client's method and the workbench's form are made from them (api.routers.job_routes).
The stored spec is the request as JSON; a kind reads it back as its typed spec (`Spec`), never
field by field from the dict.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar, Protocol, TypeVar

from pydantic import BaseModel, ConfigDict, ValidationError

from flexmech.models.errors import MechanismError, pointer_of
from flexmech.service.requests import Limits

JSON = dict[str, Any]  # a stored spec, plan, task or point: JSON objects


@dataclass(frozen=True)
class Plan:
    total: int  # points
    meta: dict[str, Any] = field(default_factory=dict)  # JSON-able facts for result(): units, names


class JobOptions(BaseModel):
    """A kind's own request fields; each field's description is the help the API, the client
    and the workbench show."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


StoredJobT = TypeVar("StoredJobT", bound="StoredJob")


class StoredJob(BaseModel):
    """What every stored job holds besides its kind's options: the mechanism and how to solve it."""

    model_config = ConfigDict(extra="ignore")

    document: dict[str, Any]
    model: str | None = None
    overrides: dict[str, float | str] | None = None
    options: dict[str, Any] | None = None  # Newton options as given: service.requests.newton_options checks them


def read_spec(model: type[StoredJobT], stored: JSON) -> StoredJobT:
    """A stored spec as the kind's typed spec; a problem (a Python caller's spec: the API's
    have been checked already) is a MechanismError naming the field."""
    try:
        return model.model_validate(stored)
    except ValidationError as exc:
        first = exc.errors()[0]
        raise MechanismError(pointer_of(tuple(first["loc"])), first["msg"].removeprefix("Value error, ")) from None


class JobKind(Protocol):
    name: str
    paged: bool  # its result lists its points, so GET /result may page them (False: it needs them all)
    Options: ClassVar[type[JobOptions]]
    route: str  # POST /v1/<route>
    operation_id: str
    request_name: str  # its request's name in the OpenAPI document
    title: str
    summary: str
    description: str
    examples: list[JSON]

    def prepare(self, spec: JSON, limits: Limits) -> Plan: ...

    def tasks(self, spec: JSON, plan: JSON, finished: Mapping[int, JSON], chunk_size: int) -> list[JSON]: ...

    def follow_up(
        self, spec: JSON, plan: JSON, task: JSON, finished: Mapping[int, JSON], chunk_size: int
    ) -> list[JSON]: ...

    def run(self, spec: JSON, task: JSON) -> list[tuple[int, JSON]]: ...

    def failed(self, point: JSON) -> bool: ...

    def result(self, spec: JSON, plan: JSON, finished: Mapping[int, JSON]) -> JSON: ...


class InOrder(ABC):
    """A kind whose points run in order, a chunk at a time, each chunk from the last stored
    point (a path, a simulation): one task at a time, the next once its points are stored."""

    @abstractmethod
    def next_chunk(self, plan: JSON, finished: Mapping[int, JSON], chunk_size: int) -> JSON | None:
        """The next task (None when every point is stored)."""

    def tasks(self, spec: JSON, plan: JSON, finished: Mapping[int, JSON], chunk_size: int) -> list[JSON]:
        task = self.next_chunk(plan, finished, chunk_size)
        return [task] if task is not None else []

    def follow_up(
        self, spec: JSON, plan: JSON, task: JSON, finished: Mapping[int, JSON], chunk_size: int
    ) -> list[JSON]:
        return self.tasks(spec, plan, finished, chunk_size)


def unfinished_part(task: JSON, finished: Mapping[int, JSON]) -> JSON | None:
    """The task with only its unfinished points (`indices`, and `values` beside them when it
    carries them); None when none is left."""
    keep = [k for k, i in enumerate(task["indices"]) if i not in finished]
    if not keep:
        return None
    rest = dict(task, indices=[task["indices"][k] for k in keep])
    if isinstance(task.get("values"), list):
        rest["values"] = [task["values"][k] for k in keep]
    return rest


def task_remainder(kind: Any, task: JSON, finished: Mapping[int, JSON]) -> JSON | None:
    """What a task that gave its worker up (service.jobs.fair_share) leaves to do, once its points
    are stored: None for a kind whose points run in order (its follow_up plans the next chunk
    from the stored points), else the task's unfinished points, as the kind's `remainder` says
    if it has one."""
    own = getattr(kind, "remainder", None)
    if own is not None:
        rest: JSON | None = own(task, finished)
        return rest
    if isinstance(kind, InOrder):
        return None
    return unfinished_part(task, finished)
