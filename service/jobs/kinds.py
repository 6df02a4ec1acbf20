"""The registry of job kinds (one line per kind), and the function workers run.

The kinds are loaded when first asked for, not when this module is imported, so a worker
loads the solvers only when it first runs a task. The contract is service.jobs.base.
"""

from __future__ import annotations

from functools import lru_cache

from service.jobs.base import JobKind, Plan
from service.threads import single_threaded_blas

__all__ = ["JobKind", "Plan", "job_kinds", "kind_named", "run_task"]


@lru_cache(maxsize=1)
def job_kinds() -> dict[str, JobKind]:
    from service.jobs.contact import CONTACT
    from service.jobs.impact_study import IMPACT_STUDY
    from service.jobs.optimize import OPTIMIZE
    from service.jobs.simulation import SIMULATION
    from service.jobs.sweep import SWEEP

    return {
        kind.name: kind
        for kind in (
            SWEEP,
            OPTIMIZE,
            CONTACT,
            SIMULATION,
            IMPACT_STUDY,
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
    return kind_named(kind).run(spec, task)
