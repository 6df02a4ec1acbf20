"""What the app builds at start-up and tears down at shutdown (see api.app's lifespan)."""

from __future__ import annotations

import asyncio
import hashlib
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import partial

from service.requests import Limits
from service.examples import ExampleLibrary
from service.jobs.executors import TaskExecutor
from service.jobs.runner import JobRunner
from service.kernels.queue import BuilderProcess
from service.jobs.store import JobStore
from service.settings import Settings


class SolverThread:
    """All CasADi work of the server process runs on this one thread. CasADi Functions are
    shared per structure (models.assembly caches them) and must not be called from several
    threads at once; one thread also keeps /v1/solve latency steady under load."""

    def __init__(self):
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="flexmech-solver")

    async def call(self, fn, *args, **kwargs):
        return await asyncio.get_running_loop().run_in_executor(self._pool, partial(fn, *args, **kwargs))

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)


@dataclass
class Services:
    settings: Settings
    limits: Limits
    store: JobStore
    executor: TaskExecutor
    runner: JobRunner
    solver: SolverThread
    examples: ExampleLibrary
    builder: BuilderProcess | None = None

    def owner_of(self, api_key: str | None) -> str:
        """Who owns the jobs a key makes: a digest of the key (the key itself is never stored);
        "" when the service runs without keys."""
        if not self.settings.api_keys or api_key is None:
            return ""
        return hashlib.sha256(api_key.encode()).hexdigest()[:32]
