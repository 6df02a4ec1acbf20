"""The FastAPI application factory. Nothing is built at import: `create_app()` makes an app
whose lifespan opens the job store, starts the executor and the job runner (which takes up
jobs a previous process left running), and closes them again at shutdown.

    uvicorn --factory flexmech.api.app:create_app          (or: flexmech serve)
"""

from __future__ import annotations

import logging
import os
from contextlib import asynccontextmanager

from fastapi import FastAPI
from fastapi_offline import FastAPIOffline

from flexmech.api import body_parsing
from flexmech.api.analysis_requests import documented
from flexmech.api.answer_cache import AnswerCache
from flexmech.api.errors import install_error_handlers
from flexmech.api.headers import SecurityHeaders
from flexmech.api.limits import BodySizeLimit, JsonBody
from flexmech.api.routers import drawings, examples, health, jobs, usage
from flexmech.api.routers.job_routes import job_router
from flexmech.api.routers.solve import solve_router
from flexmech.api.routers.workbench import mount_workbench
from flexmech.api.solver_pool import SolverPool
from flexmech.api.state import Services
from flexmech.service.analyses import ANALYSES
from flexmech.service.examples import ExampleLibrary, examples_directory
from flexmech.service.jobs.executors import make_executor
from flexmech.service.jobs.kinds import job_kinds
from flexmech.service.jobs.retention import RetentionPurge
from flexmech.service.jobs.runner import JobRunner
from flexmech.service.jobs.store import JobStore
from flexmech.service.kernels.builder_process import BuilderProcess
from flexmech.service.kernels.cache import compiler
from flexmech.service.settings import Settings

log = logging.getLogger("flexmech.api")

DESCRIPTION = """\
Kinetostatics of planar compliant mechanisms over HTTP.

Numbers are in the units the mechanism document declares. Long work is a job: POST returns
202 and a job to follow at /v1/jobs/{id}. Every error has the shape
`{"error": {"status", "code", "message", "pointer"}}`; `pointer` is the JSON pointer of the
offending field of the request body, when there is one.
"""


def _services(settings: Settings) -> Services:
    store = JobStore(settings.resolved_database_url(), settings.quotas())
    executor = make_executor(settings.dask_address, settings.workers, settings.data_dir)
    runner = JobRunner(store, executor, settings.chunk_size, settings.job_time_limit)
    limits = settings.limits()
    library = ExampleLibrary(examples_directory(settings.examples_dir))
    services = Services(settings, limits, store, executor, runner, SolverPool(settings.solver_workers), library)
    services.retention = RetentionPurge(store, settings.job_retention)
    return services


def _builder(settings: Settings) -> BuilderProcess | None:
    """The build queue's process (service.kernels.queue), when kernels are built here: watched,
    and started again when it ends (/v1/health says "degraded" meanwhile)."""
    if not settings.build_kernels or compiler() is None:
        return None
    builder = BuilderProcess(
        {
            "FLEXMECH_BUILD_SECONDS": str(settings.build_seconds),
            "FLEXMECH_BUILD_MEMORY_BYTES": str(int(settings.build_memory_mb * 2**20)),
            "FLEXMECH_BUILD_QUEUE_MAX": str(settings.build_queue_max),  # the workers' requests keep to it too
        }
    )
    builder.start()
    log.info("kernel builder started (pid %d)", builder.pid)
    return builder


def create_app(settings: Settings | None = None) -> FastAPI:
    settings = settings or Settings()

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        if settings.cache_max_bytes is not None:
            os.environ["FLEXMECH_CACHE_MAX_BYTES"] = str(settings.cache_max_bytes)  # workers and builder too
        builder = _builder(settings)  # before the executor: its workers inherit the queue's setting
        job_kinds()  # their imports (the solvers, scipy) at startup: no request waits for them
        services = _services(settings)
        services.builder = builder
        app.state.services = services
        services.runner.start()
        services.retention.start()
        log.info(
            "flexmech serving: store %s, %s",
            services.store.engine.url.render_as_string(hide_password=True),
            services.executor.description,
        )
        try:
            yield
        finally:
            services.retention.stop()
            services.runner.stop()
            if builder is not None:
                builder.stop()
            services.solver.close()
            body_parsing.close()
            services.executor.close()
            services.store.close()

    # The /docs page's scripts come from the package (fastapi-offline), not a CDN: it works offline.
    app = FastAPIOffline(title="flexmech", version="1", description=DESCRIPTION, lifespan=lifespan, redoc_url=None)
    install_error_handlers(app)
    app.include_router(solve_router())
    app.include_router(job_router())
    for module in (jobs, usage, examples, drawings, health):
        app.include_router(module.router)
    mount_workbench(app)
    app.add_middleware(JsonBody)  # the body parsed, once no kept answer was given
    app.add_middleware(AnswerCache, max_bytes=settings.answer_cache_bytes)  # inside the body guard: it reads the body
    app.add_middleware(BodySizeLimit, max_bytes=settings.max_request_bytes, read_timeout=settings.request_read_timeout)
    app.add_middleware(SecurityHeaders)  # outermost: even the body guard's answers carry them
    _list_analyses_in_schema(app)
    return app


def _list_analyses_in_schema(app: FastAPI) -> None:
    """The analyses are a registry of the service (service.analyses), not a list the client
    schemas keep: the OpenAPI schema enumerates the sweepable ones for generated clients (the
    solve request is a union over all of them already)."""
    build = app.openapi

    def openapi() -> dict:
        if app.openapi_schema is not None:
            return app.openapi_schema
        schema = documented(build())
        components = schema.get("components", {}).get("schemas", {})
        field = components.get("SweepRequest", {}).get("properties", {}).get("analysis")
        if field is not None:
            field["enum"] = [a.name for a in ANALYSES if a.sweepable]
        return schema

    app.openapi = openapi
