"""One BLAS thread per process where flexmech serves or works.

Multithreaded BLAS on a loaded 2-core machine oversubscribes the cores: a repeated solve went
from 9 ms to 1.4 s. The server's solver workers and every job worker (process pool, Dask) run with
one BLAS thread; parallelism comes from the workers themselves.
"""

from __future__ import annotations

from functools import lru_cache


@lru_cache(maxsize=1)
def single_threaded_blas() -> None:
    """Limit every BLAS and OpenMP library loaded in this process to one thread (once)."""
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1)
