"""A task's error, returned by the worker as data (a failure record), not raised across the
process boundary: an exception that pickle cannot rebuild in the server would otherwise break
the whole process pool and fail every other job's tasks with it (issue 54).

    {"task_failed": {"type": "MechanismError", "message": "/tolerance: ...",
                     "pointer": "/tolerance", "problem": "..."}}
"""

from __future__ import annotations

from typing import Any

FAILED = "task_failed"


def failure_record(error: BaseException) -> dict[str, Any]:
    """What the server needs of a task's error: its type's name, its text and, for our errors
    that name a field, the field and the problem (plain strings: they always cross)."""
    pointer, problem = getattr(error, "pointer", None), getattr(error, "problem", None)
    return {
        FAILED: {
            "type": type(error).__name__,
            "message": str(error),
            "pointer": pointer if isinstance(pointer, str) else None,
            "problem": problem if isinstance(problem, str) else None,
        }
    }


class TaskFailed(Exception):
    """A task's error as its worker reported it (failure_record), raised in the server."""

    def __init__(self, record: dict[str, Any]):
        self.record = record
        super().__init__(f"{record['type']}: {record['message']}")

    def __reduce__(self):
        return (TaskFailed, (self.record,))


def failure_in(result: Any) -> TaskFailed | None:
    """The failure a worker returned instead of points, if it did."""
    if isinstance(result, dict) and isinstance(result.get(FAILED), dict):
        return TaskFailed(result[FAILED])
    return None
