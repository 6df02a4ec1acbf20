"""The job store: jobs and their finished points, in SQLite (default) or PostgreSQL.

Each finished point is its own row, written as soon as its task returns, so a job that was
running when the server stopped keeps every point it had finished. (job_id, index) is the
primary key: a point can be written once only. A job's document is kept once however many
jobs use it (service.jobs.store_schema); quotas (service.jobs.quotas) are checked as a job is
created, in the transaction that creates it.
"""

from __future__ import annotations

import uuid
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from sqlalchemy import select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session, sessionmaker

from flexmech.service.jobs.quotas import Quotas, check_admission
from flexmech.service.jobs.store_accounting import (
    abridged,
    document_row,
    json_bytes,
    owner_uses_document,
    packed_point,
    unpacked_point,
    usage_of,
)
from flexmech.service.jobs.store_housekeeping import StoreHousekeeping
from flexmech.service.jobs.store_schema import (
    ACTIVE,
    FINAL,
    DocumentRow,
    JobRow,
    JobStatus,
    OwnerRow,
    PointRow,
    create_tables,
    make_engine,
)

__all__ = ["ACTIVE", "FINAL", "Job", "JobStatus", "JobStore", "utcnow"]

CREATE_ATTEMPTS = 3  # two keys storing one new document at once: one of them tries again


def utcnow() -> datetime:
    return datetime.now(UTC)


@dataclass(frozen=True)
class Job:
    id: str
    kind: str
    owner: str
    status: JobStatus
    spec: dict  # with its document ({} in a listing: JobStore.recent)
    plan: dict
    total: int
    done: int
    failed_points: int
    error: str | None
    created_at: datetime
    started_at: datetime | None
    finished_at: datetime | None
    restarts: int


def _aware(t: datetime | None) -> datetime | None:
    """SQLite hands back naive datetimes; they were written in UTC."""
    if t is not None and t.tzinfo is None:
        return t.replace(tzinfo=UTC)
    return t


def _job(row: JobRow, spec: dict) -> Job:
    return Job(
        row.id,
        row.kind,
        row.owner,
        row.status,  # type: ignore[arg-type]
        spec,
        row.plan,
        row.total,
        row.done,
        row.failed_points,
        row.error,
        _aware(row.created_at),  # type: ignore[arg-type]
        _aware(row.started_at),
        _aware(row.finished_at),
        row.restarts,
    )


def _spec(s: Session, row: JobRow) -> dict:
    """The job's spec with its document."""
    if row.document is None:
        return row.spec
    document = s.get(DocumentRow, row.document)
    return {"document": document.body if document is not None else {}, **row.spec}


def _lock_owner(s: Session, owner: str) -> None:
    """Take the owner's row for this transaction (a write first, so SQLite takes its write lock
    here and PostgreSQL locks the row): one job of a key is created at a time."""
    bumped = s.execute(update(OwnerRow).where(OwnerRow.owner == owner).values(jobs_created=OwnerRow.jobs_created + 1))
    if bumped.rowcount == 0:
        s.add(OwnerRow(owner=owner, jobs_created=1))
        s.flush()


class JobStore(StoreHousekeeping):
    def __init__(self, url: str, quotas: Quotas | None = None):
        self.url = url
        self.quotas = quotas  # None: no quota (a store used from Python, or by tests)
        self.engine = make_engine(url)
        create_tables(self.engine)
        self._session = sessionmaker(self.engine, expire_on_commit=False)

    def close(self) -> None:
        self.engine.dispose()

    # --- jobs -------------------------------------------------------------------------------
    def create(self, kind: str, owner: str, spec: dict, plan: dict, total: int, document: dict | None = None) -> Job:
        """Store a new job: its spec, and its document (read back as the spec's "document");
        QuotaExceeded (nothing stored) when it would take its owner past a quota. The document
        is stored unless a job already holds the same one."""
        for attempt in range(CREATE_ATTEMPTS):
            try:
                return self._create(kind, owner, spec, plan, total, document)
            except IntegrityError:  # another key stored (or the last user deleted) the document
                if attempt == CREATE_ATTEMPTS - 1:
                    raise
        raise AssertionError("unreachable")

    def _create(self, kind: str, owner: str, spec: dict, plan: dict, total: int, document: dict | None) -> Job:
        now = utcnow()
        stored = document_row(document, now) if document is not None else None
        row = JobRow(
            id=uuid.uuid4().hex,
            kind=kind,
            owner=owner,
            status="queued",
            spec=spec,
            plan=plan,
            total=total,
            done=0,
            failed_points=0,
            created_at=now,
            restarts=0,
            document=stored.digest if stored is not None else None,
            bytes=json_bytes(spec) + json_bytes(plan),
        )
        with self._session.begin() as s:
            _lock_owner(s, owner)
            if self.quotas is not None:
                shared = stored is None or owner_uses_document(s, owner, stored.digest)
                needed = row.bytes + (0 if shared else stored.bytes)  # type: ignore[union-attr]
                check_admission(usage_of(s, owner), self.quotas, needed)
            if stored is not None and s.get(DocumentRow, stored.digest) is None:
                s.add(stored)
                s.flush()
            s.add(row)
        return _job(row, spec if document is None else {"document": document, **spec})

    def get(self, job_id: str) -> Job | None:
        with self._session() as s:
            row = s.get(JobRow, job_id)
            return _job(row, _spec(s, row)) if row is not None else None

    def statuses(self, job_ids: Iterable[str]) -> dict[str, str]:
        """The status of each of the jobs that still exist (a deleted job is left out)."""
        ids = list(job_ids)
        if not ids:
            return {}
        with self._session() as s:
            return dict(s.execute(select(JobRow.id, JobRow.status).where(JobRow.id.in_(ids))).all())

    def recent(self, owner: str, limit: int) -> list[tuple[Job, str]]:
        """The owner's newest jobs first, each with its document's name abridged (for a list
        of them; their specs are left out: {})."""
        query = (
            select(JobRow, DocumentRow.name)
            .outerjoin(DocumentRow, JobRow.document == DocumentRow.digest)
            .where(JobRow.owner == owner)
            .order_by(JobRow.created_at.desc())
            .limit(limit)
        )
        with self._session() as s:
            return [(_job(r, {}), _listed_name(r, name)) for r, name in s.execute(query)]

    def active(self) -> list[Job]:
        """Jobs queued or running, oldest first."""
        with self._session() as s:
            rows = s.scalars(select(JobRow).where(JobRow.status.in_(ACTIVE)).order_by(JobRow.created_at))
            return [_job(r, _spec(s, r)) for r in rows]

    def mark_started(self, job_id: str, resumed: bool) -> None:
        with self._session.begin() as s:
            row = s.get(JobRow, job_id)
            if row is None or row.status in FINAL:
                return
            row.status = "running"
            if row.started_at is None:
                row.started_at = utcnow()
            if resumed:
                row.restarts += 1

    def finish(self, job_id: str, status: JobStatus, error: str | None = None) -> bool:
        """Move an active job to a final status. False when it was already final (for
        example cancelled while its last task ran) or deleted: a final status never changes."""
        with self._session.begin() as s:
            result = s.execute(
                update(JobRow)
                .where(JobRow.id == job_id, JobRow.status.in_(ACTIVE))
                .values(status=status, error=error, finished_at=utcnow())
            )
            return result.rowcount == 1

    # --- points -----------------------------------------------------------------------------
    def add_points(
        self, job_id: str, points: Iterable[tuple[int, dict[str, Any]]], failed: Callable[[dict], bool] | None = None
    ) -> int:
        """Store finished points and advance the job's progress and bytes in one transaction.
        Points already stored are left as they are (never overwritten); points of a deleted
        job are dropped. Returns how many were new. Which points count as failed is the job
        kind's to say (`failed`, by default the kind of the job asked); the store only counts
        them."""
        points = list(points)
        if not points:
            return 0
        if failed is None:
            failed = self._kind_of(job_id).failed
        with self._session.begin() as s:
            if s.get(JobRow, job_id) is None:
                return 0
            have = set(
                s.scalars(
                    select(PointRow.index).where(PointRow.job_id == job_id, PointRow.index.in_([i for i, _ in points]))
                )
            )
            now = utcnow()
            new = [(i, d) for i, d in points if i not in have]
            stored = [(i, *packed_point(d)) for i, d in new]
            s.add_all(PointRow(job_id=job_id, index=i, data=d, packed=p, finished_at=now) for i, d, p, _ in stored)
            new_failed = sum(1 for _, d in new if failed(d))
            s.execute(
                update(JobRow)
                .where(JobRow.id == job_id)
                .values(
                    done=JobRow.done + len(new),
                    failed_points=JobRow.failed_points + new_failed,
                    bytes=JobRow.bytes + sum(size for *_, size in stored),
                )
            )
        return len(new)

    def _kind_of(self, job_id: str):
        from flexmech.service.jobs.kinds import kind_named  # the kinds load the solvers: only when asked

        job = self.get(job_id)
        if job is None:
            raise KeyError(f"no job '{job_id}'")
        return kind_named(job.kind)

    def points(self, job_id: str, offset: int = 0, limit: int | None = None) -> dict[int, dict]:
        """Stored points by index, in index order; a page of them with offset and limit."""
        query = (
            select(PointRow.index, PointRow.data, PointRow.packed)
            .where(PointRow.job_id == job_id)
            .order_by(PointRow.index)
        )
        if offset:
            query = query.offset(offset)
        if limit is not None:
            query = query.limit(limit)
        with self._session() as s:
            return {i: unpacked_point(d, p) for i, d, p in s.execute(query)}


def _listed_name(row: JobRow, name: str | None) -> str:
    if name is not None:
        return name
    document = (row.spec or {}).get("document") or {}  # a job stored before documents were kept apart
    return abridged(str(document.get("name", "")))
