"""The service's settings: one class, read from FLEXMECH_* environment variables.

FLEXMECH_DATABASE_URL=postgresql+psycopg://user:pw@db/flexmech   (default: SQLite file)
FLEXMECH_DASK_ADDRESS=tcp://scheduler:8786                        (default: a process pool)
FLEXMECH_API_KEYS=key-one,key-two                                 (default: no keys, open)
FLEXMECH_KEY_MAX_BYTES=500MB  FLEXMECH_JOB_RETENTION=P7D            (quotas per key, retention)
"""

from __future__ import annotations

import os
from datetime import timedelta
from pathlib import Path
from typing import Annotated, Literal

from pydantic import ByteSize, Field, field_validator
from pydantic_settings import BaseSettings, NoDecode, SettingsConfigDict

from flexmech.service.costs import Limits
from flexmech.service.jobs.quotas import Quotas


def default_data_dir() -> Path:
    """Where the embedded SQLite store lives: $XDG_DATA_HOME/flexmech or ~/.local/share/flexmech."""
    base = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    return Path(base) / "flexmech"


class Settings(BaseSettings):
    model_config = SettingsConfigDict(env_prefix="FLEXMECH_", extra="ignore")

    host: str = "127.0.0.1"
    port: int = Field(8000, ge=1, le=65535)
    data_dir: Path = Field(default_factory=default_data_dir)
    database_url: str | None = None  # None: SQLite file data_dir/flexmech.db
    dask_address: str | None = None  # set: sweeps run on that Dask cluster
    workers: int = Field(default_factory=lambda: max(1, os.cpu_count() or 1), ge=1, le=256)
    solver_workers: int = Field(
        default_factory=lambda: max(1, os.cpu_count() or 1),
        ge=1,
        le=64,
        description="processes that run /v1/solve, drawings and job preparation",
    )
    examples_dir: Path | None = None  # None: the examples installed with the package

    # Access: with keys set, every /v1 request but /v1/health needs X-API-Key.
    api_keys: Annotated[list[str], NoDecode] = Field(default_factory=list)

    # What one key may keep in the job store (service.jobs.quotas); without keys, the service
    key_max_jobs: int = Field(10_000, ge=1, description="jobs one key may keep stored")
    key_max_bytes: ByteSize = Field(
        ByteSize(1_000_000_000),
        ge=100_000,
        description="bytes one key may keep stored (specs, documents, results, archives); 1GB, 500MiB, or bytes",
    )
    key_max_running: int = Field(20, ge=1, description="jobs one key may have queued or running")
    job_retention: timedelta = Field(
        timedelta(days=30),
        gt=timedelta(0),
        description="how long a job is kept after it ends (seconds, or ISO 8601 like P30D); then it is purged",
    )

    # Limits (service.costs): every request is costed against them before anything is built
    max_request_bytes: int = Field(1_000_000, ge=1024)
    request_read_timeout: float = Field(10.0, gt=0, description="seconds to receive a request's body")
    header_read_timeout: float = Field(
        10.0,
        gt=0,
        description="seconds a connection has to send a request's "
        "headers, from connecting or from its first bytes after an answer",
    )
    max_elements: int = Field(200, ge=1)
    max_bodies: int = Field(200, ge=1)
    max_loads: int = Field(500, ge=1)
    max_outputs: int = Field(500, ge=1, description="named outputs of a document")
    max_link_work: int = Field(8192, ge=1, description="intervals x order^2 summed over links")
    max_link_elements: int = Field(64, ge=1, le=128, description="elements of one link by elements")
    max_sweep_points: int = Field(20_000, ge=1)
    max_result_values: int = Field(1_000_000, ge=1, description="numbers a job stores")
    max_contact_rows: int = Field(2000, ge=1, description="non-penetration rows of a contact problem")
    max_contact_rotations: int = Field(128, ge=1, description="rotations of a contact problem's links")
    max_simulation_steps: int = Field(1_000_000, ge=1, description="time steps of a simulation job")
    max_export_unknowns: int = Field(400, ge=1, description="unknowns of a mechanism exported as a C library")
    max_response_bytes: int = Field(
        20_000_000, ge=100_000, description="bytes of JSON in one /v1/solve answer (larger reports run as jobs)"
    )
    answer_cache_bytes: int = Field(
        64_000_000, ge=0, description="memory for /v1/solve answers kept for the same request and key (0: none)"
    )
    solve_time_limit: float = Field(10.0, gt=0, description="seconds of Newton per /v1/solve")
    job_time_limit: float = Field(3600.0, gt=0, description="seconds of wall time per job")
    chunk_size: int = Field(8, ge=1, le=10_000, description="points per task sent to a worker")
    build_kernels: bool = Field(
        True,
        description="compile kernels in a build queue beside the server (runs go "
        "on interpreted until a kernel is built)",
    )
    build_seconds: float = Field(60.0, gt=0, description="time limit of one kernel compile")
    build_memory_mb: float = Field(1024.0, gt=64, description="memory limit (MiB) of one kernel compile")
    build_queue_max: int = Field(
        32,
        ge=1,
        le=10_000,
        description="builds the kernel build queue holds at most: over it the least recently asked is dropped (logged)",
    )
    cache_max_bytes: int | None = Field(
        None,
        ge=1_000_000,
        description="bound of the disk cache of graphs and kernels (least recently used evicted); default 2 GiB",
    )
    log_level: Literal["debug", "info", "warning", "error"] = "info"

    @field_validator("job_retention", mode="before")
    @classmethod
    def _seconds(cls, value):
        """A bare number is seconds (pydantic reads only ISO 8601 and [D days,] HH:MM:SS from text)."""
        if isinstance(value, str):
            try:
                return float(value)
            except ValueError:
                return value
        return value

    @field_validator("api_keys", mode="before")
    @classmethod
    def _split_keys(cls, value):
        if isinstance(value, str):
            keys = [k.strip() for k in value.split(",") if k.strip()]
            if value and not keys:  # " " or " , ," would run the server open by accident
                raise ValueError("lists no key, only blanks or commas (leave it empty to run without keys)")
            return keys
        return value

    @field_validator("api_keys")
    @classmethod
    def _keys_long_enough(cls, keys: list[str]) -> list[str]:
        short = [k for k in keys if len(k) < 16]
        if short:
            raise ValueError(f"{len(short)} API key(s) shorter than 16 characters")
        return keys

    def limits(self) -> Limits:
        return Limits(
            max_elements=self.max_elements,
            max_sweep_points=self.max_sweep_points,
            solve_time_limit=self.solve_time_limit,
            max_bodies=self.max_bodies,
            max_loads=self.max_loads,
            max_outputs=self.max_outputs,
            max_link_work=self.max_link_work,
            max_link_elements=self.max_link_elements,
            max_result_values=self.max_result_values,
            job_time_limit=self.job_time_limit,
            max_contact_rows=self.max_contact_rows,
            max_contact_rotations=self.max_contact_rotations,
            max_simulation_steps=self.max_simulation_steps,
            max_export_unknowns=self.max_export_unknowns,
            max_response_bytes=self.max_response_bytes,
        )

    def quotas(self) -> Quotas:
        return Quotas(self.key_max_jobs, int(self.key_max_bytes), self.key_max_running)

    def resolved_database_url(self) -> str:
        if self.database_url:
            return self.database_url
        return f"sqlite:///{self.data_dir / 'flexmech.db'}"
