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
Tasks and point data are JSON-able dicts, so they travel to process pools and Dask workers
and are stored as they are. The runner and the store know nothing else about a kind.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

from service.requests import Limits

JSON = dict[str, Any]  # a stored spec, plan, task or point: JSON objects


@dataclass(frozen=True)
class Plan:
    total: int  # points
    meta: dict[str, Any] = field(default_factory=dict)  # JSON-able facts for result(): units, names


class JobKind(Protocol):
    name: str
    paged: bool  # its result lists its points, so GET /result may page them (False: it needs them all)

    def prepare(self, spec: JSON, limits: Limits) -> Plan: ...

    def tasks(self, spec: JSON, plan: JSON, finished: Mapping[int, JSON], chunk_size: int) -> list[JSON]: ...

    def follow_up(
        self, spec: JSON, plan: JSON, task: JSON, finished: Mapping[int, JSON], chunk_size: int
    ) -> list[JSON]: ...

    def run(self, spec: JSON, task: JSON) -> list[tuple[int, JSON]]: ...

    def failed(self, point: JSON) -> bool: ...

    def result(self, spec: JSON, plan: JSON, finished: Mapping[int, JSON]) -> JSON: ...


class InOrder:
    """A kind whose points run in order, a chunk at a time, each chunk from the last stored
    point (a path, a simulation): one task at a time, the next once its points are stored.
    Subclasses say next_chunk(plan, finished, chunk_size) -> task or None."""

    def next_chunk(self, plan: JSON, finished: Mapping[int, JSON], chunk_size: int) -> JSON | None:
        raise NotImplementedError

    def tasks(self, spec: JSON, plan: JSON, finished: Mapping[int, JSON], chunk_size: int) -> list[JSON]:
        task = self.next_chunk(plan, finished, chunk_size)
        return [task] if task is not None else []

    def follow_up(
        self, spec: JSON, plan: JSON, task: JSON, finished: Mapping[int, JSON], chunk_size: int
    ) -> list[JSON]:
        return self.tasks(spec, plan, finished, chunk_size)
