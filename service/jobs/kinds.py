"""The registry of job kinds (one line per kind), and the function workers run.

The built-in kinds are loaded when first asked for, not when this module is imported, so a
worker loads the solvers only when it first runs a task; a plugin module (FLEXMECH_PLUGINS)
adds its own with one line, `register_job_kind(...)`. The contract is service.jobs.base.
"""

from __future__ import annotations

from functools import lru_cache

from flexmech.service.deadline import stop_scope
from flexmech.service.jobs.base import JobKind, Plan
from flexmech.service.jobs.control import TaskControl
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


def run_task(kind: str, spec: dict, task: dict) -> list[tuple[int, dict]]:
    """The function workers execute (a module-level name, so pools and Dask can ship it)."""
    single_threaded_blas()
    with stop_scope(TaskControl(task).should_stop):  # Newton and the other loops end on a cancel too
        return kind_named(kind).run(spec, task)
