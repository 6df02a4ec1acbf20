"""What the app builds at start-up and tears down at shutdown (see api.app's lifespan)."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

from flexmech.api.solver_pool import SolverPool
from flexmech.service.examples import ExampleLibrary
from flexmech.service.jobs.executors import TaskExecutor
from flexmech.service.jobs.retention import RetentionPurge
from flexmech.service.jobs.runner import JobRunner
from flexmech.service.jobs.store import JobStore
from flexmech.service.kernels.builder_process import BuilderProcess
from flexmech.service.requests import Limits
from flexmech.service.settings import Settings


@dataclass
class Services:
    settings: Settings
    limits: Limits
    store: JobStore
    executor: TaskExecutor
    runner: JobRunner
    solver: SolverPool
    examples: ExampleLibrary
    builder: BuilderProcess | None = None
    retention: RetentionPurge | None = None

    def owner_of(self, api_key: str | None) -> str:
        """Who owns the jobs a key makes: a digest of the key (the key itself is never stored);
        "" when the service runs without keys."""
        if not self.settings.api_keys or api_key is None:
            return ""
        return hashlib.sha256(api_key.encode()).hexdigest()[:32]
