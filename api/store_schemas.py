"""Responses about what the job store holds: a key's usage against its quotas (GET /v1/usage),
a deleted job (DELETE /v1/jobs/{id}), and the store's totals in /v1/health."""

from __future__ import annotations

from pydantic import BaseModel, Field

from flexmech.api.schemas import HealthResponse  # the light client reads these: no service import


class QuotaUse(BaseModel):
    used: int
    limit: int


class UsageResponse(BaseModel):
    jobs: QuotaUse = Field(description="jobs stored (FLEXMECH_KEY_MAX_JOBS)")
    running: QuotaUse = Field(description="jobs queued or running (FLEXMECH_KEY_MAX_RUNNING)")
    bytes: QuotaUse = Field(
        description="bytes stored: specs, results and archives as stored, each document once (FLEXMECH_KEY_MAX_BYTES)"
    )
    retention_seconds: float = Field(description="a job is purged this long after it ends (FLEXMECH_JOB_RETENTION)")
    free: str = Field(description="how to free stored jobs and bytes")


class JobDeletedResponse(BaseModel):
    id: str
    deleted: bool = True
    status: str = Field(description="the job's status when it was deleted (an active job was cancelled first)")
    freed_bytes: int = Field(description="bytes the key got back (its document's too, when no other job of it uses it)")
    usage: UsageResponse


class StoreTotals(BaseModel):
    jobs: int = Field(description="jobs stored, every key's")
    running: int = Field(description="jobs queued or running")
    documents: int = Field(description="documents stored (each once, however many jobs use it)")
    bytes: int = Field(description="bytes the jobs and documents hold, as quotas count them")
    database_bytes: int | None = Field(
        description="the database's size on disk (SQLite: its file and write-ahead log; PostgreSQL: the database)"
    )
    per_key: dict[str, int] = Field(description="each key's quotas: max_jobs, max_bytes, max_running")
    retention_seconds: float


class HealthReport(HealthResponse):
    store: StoreTotals = Field(description="what the job store holds, for the operator")
