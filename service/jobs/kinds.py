"""The registry of job kinds (one line per kind), and the function workers run.

The built-in kinds are loaded when first asked for, not when this module is imported, so a
worker loads the solvers only when it first runs a task; a plugin module (FLEXMECH_PLUGINS)
adds its own with one line, `register_job_kind(...)`. The contract is service.jobs.base.
"""

from __future__ import annotations

import contextlib
import os
from functools import lru_cache
from pathlib import Path

from flexmech.service.deadline import stop_scope
from flexmech.service.jobs.base import JobKind, Plan
from flexmech.service.jobs.control import TaskControl
from flexmech.service.jobs.failures import failure_record
from flexmech.service.threads import single_threaded_blas

__all__ = ["JobKind", "Plan", "job_kinds", "kind_named", "register_job_kind", "run_task"]

_REGISTERED: dict[str, JobKind] = {}  # kinds of plugins, beside the built-in ones


def register_job_kind(kind: JobKind) -> JobKind:
    """Add a kind: the app made after this serves its route (api.routers.job_routes)."""
    if _REGISTERED.get(kind.name, kind) is not kind:
        raise ValueError(f"a job kind named '{kind.name}' is registered already")
    _REGISTERED[kind.name] = kind  # (not checked against the built-in ones here: loading them may load this plugin)
    return kind


def job_kinds() -> dict[str, JobKind]:
    """Every kind: the built-in ones, then the registered ones."""
    built_in = _built_in()
    taken = sorted(set(built_in) & set(_REGISTERED))
    if taken:
        raise ValueError(f"a registered job kind has a built-in kind's name: {', '.join(taken)}")
    return {**built_in, **_REGISTERED}


@lru_cache(maxsize=1)
def _built_in() -> dict[str, JobKind]:
    from flexmech.service.jobs.analysis import ANALYSIS_JOB
    from flexmech.service.jobs.contact import CONTACT
    from flexmech.service.jobs.export import EXPORT
    from flexmech.service.jobs.impact_study import IMPACT_STUDY
    from flexmech.service.jobs.optimize import OPTIMIZE
    from flexmech.service.jobs.simulation import SIMULATION
    from flexmech.service.jobs.sweep import SWEEP

    return {
        kind.name: kind
        for kind in (
            SWEEP,
            OPTIMIZE,
            CONTACT,
            SIMULATION,
            IMPACT_STUDY,
            EXPORT,
            ANALYSIS_JOB,
        )
    }


def kind_named(name: str) -> JobKind:
    kinds = job_kinds()
    try:
        return kinds[name]
    except KeyError:
        raise KeyError(f"unknown job kind '{name}' (kinds: {', '.join(sorted(kinds))})") from None


def run_task(kind: str, spec: dict, task: dict) -> list[tuple[int, dict]] | dict:
    """The function workers execute (a module-level name, so pools and Dask can ship it): the
    task's points, or a failure record (service.jobs.failures) when it raised."""
    single_threaded_blas()
    pid_file = (task.get("control") or {}).get("pid_file")
    if pid_file:  # which worker runs it: if that worker dies, the runner charges this task only
        with contextlib.suppress(OSError):  # a full disk: the task runs, uncharged if its worker dies
            Path(pid_file).write_text(str(os.getpid()))
    with stop_scope(TaskControl(task).should_stop):  # Newton and the other loops end on a cancel too
        try:
            return kind_named(kind).run(spec, task)
        except Exception as error:  # as data: an error that cannot cross would break the pool (issue 54)
            return failure_record(error)
