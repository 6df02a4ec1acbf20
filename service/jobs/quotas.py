"""What one key may keep in the job store, and what it keeps.

Three quotas (service.settings: FLEXMECH_KEY_MAX_JOBS, _MAX_BYTES, _MAX_RUNNING): jobs stored,
bytes stored (specs, plans, points and archives as stored, and each document the key's jobs
use, once), and jobs queued or running. Without API keys every caller is one owner, so the
quotas bound the whole service. A new job over a quota is refused (HTTP 429 saying what is
used, the limit and how to free it); a running job whose points take its key past the byte
quota stops there, its points so far kept.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass


@dataclass(frozen=True)
class Quotas:
    max_jobs: int
    max_bytes: int
    max_running: int


@dataclass(frozen=True)
class Usage:
    jobs: int
    running: int
    bytes: int

    def against(self, quotas: Quotas) -> dict:
        """{"jobs": {"used", "limit"}, "running": ..., "bytes": ...}: for /v1/usage and /v1/health."""
        limits = {"jobs": quotas.max_jobs, "running": quotas.max_running, "bytes": quotas.max_bytes}
        return {name: {"used": used, "limit": limits[name]} for name, used in asdict(self).items()}


FREE_HINT = {
    "jobs": "delete jobs you no longer need (DELETE /v1/jobs/{id}; GET /v1/jobs lists them)",
    "bytes": "delete jobs you no longer need (DELETE /v1/jobs/{id} frees their bytes at once)",
    "running": "wait for a job to finish, or cancel one (POST /v1/jobs/{id}/cancel)",
}
WHAT = {"jobs": "stored jobs", "bytes": "stored bytes", "running": "jobs queued or running"}


class QuotaExceeded(Exception):
    """A new job would take its key past a quota."""

    def __init__(self, quota: str, used: int, limit: int, needed: int = 1):
        self.quota, self.used, self.limit, self.needed = quota, used, limit, needed
        super().__init__(
            f"quota of {WHAT[quota]} reached: {used} used of {limit}"
            + (f", this job needs {needed} more" if quota == "bytes" else "")
            + f"; to free it, {FREE_HINT[quota]}"
        )

    def __reduce__(self):  # pickled across processes with its fields
        return (QuotaExceeded, (self.quota, self.used, self.limit, self.needed))

    def details(self) -> dict:
        return {"quota": self.quota, "used": self.used, "limit": self.limit, "free": FREE_HINT[self.quota]}


def check_admission(usage: Usage, quotas: Quotas, new_bytes: int) -> None:
    """Raise QuotaExceeded when one more job of `new_bytes` would pass one of the quotas."""
    if usage.jobs + 1 > quotas.max_jobs:
        raise QuotaExceeded("jobs", usage.jobs, quotas.max_jobs)
    if usage.running + 1 > quotas.max_running:
        raise QuotaExceeded("running", usage.running, quotas.max_running)
    if usage.bytes + new_bytes > quotas.max_bytes:
        raise QuotaExceeded("bytes", usage.bytes, quotas.max_bytes, new_bytes)
