"""The job store: jobs and their finished points, in SQLite (default) or PostgreSQL.

Each finished point is its own row, written as soon as its task returns, so a job that was
running when the server stopped keeps every point it had finished. (job_id, index) is the
primary key: a point can be written once only.
"""

from __future__ import annotations

import uuid
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, Literal

from sqlalchemy import JSON, DateTime, ForeignKey, Integer, String, Text, create_engine, event, select, update
from sqlalchemy.engine import Engine, make_url
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, sessionmaker

JobStatus = Literal["queued", "running", "succeeded", "failed", "cancelled"]
ACTIVE: tuple[JobStatus, ...] = ("queued", "running")
FINAL: tuple[JobStatus, ...] = ("succeeded", "failed", "cancelled")


def utcnow() -> datetime:
    return datetime.now(UTC)


class _Base(DeclarativeBase):
    pass


class JobRow(_Base):
    __tablename__ = "flexmech_jobs"

    id: Mapped[str] = mapped_column(String(32), primary_key=True)
    kind: Mapped[str] = mapped_column(String(32))
    owner: Mapped[str] = mapped_column(String(64), index=True)
    status: Mapped[str] = mapped_column(String(16), index=True)
    spec: Mapped[dict] = mapped_column(JSON)
    plan: Mapped[dict] = mapped_column(JSON)  # the kind's facts about the spec (units, grid)
    total: Mapped[int] = mapped_column(Integer)
    done: Mapped[int] = mapped_column(Integer, default=0)
    failed_points: Mapped[int] = mapped_column(Integer, default=0)
    error: Mapped[str | None] = mapped_column(Text, nullable=True)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    started_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)
    finished_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)
    restarts: Mapped[int] = mapped_column(Integer, default=0)


class PointRow(_Base):
    __tablename__ = "flexmech_job_points"

    job_id: Mapped[str] = mapped_column(
        String(32), ForeignKey("flexmech_jobs.id", ondelete="CASCADE"), primary_key=True
    )
    index: Mapped[int] = mapped_column(Integer, primary_key=True)
    data: Mapped[dict] = mapped_column(JSON)
    finished_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))


@dataclass(frozen=True)
class Job:
    id: str
    kind: str
    owner: str
    status: JobStatus
    spec: dict
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


def _job(row: JobRow) -> Job:
    return Job(
        row.id,
        row.kind,
        row.owner,
        row.status,
        row.spec,
        row.plan,
        row.total,
        row.done,
        row.failed_points,
        row.error,
        _aware(row.created_at),
        _aware(row.started_at),
        _aware(row.finished_at),
        row.restarts,
    )


# How long a write waits for another writer's lock on an SQLite file before it fails: a
# request then answers 503 with Retry-After at once instead of holding its client, and the
# runner retries its points with backoff (service.jobs.store_guard), so nothing is lost.
SQLITE_BUSY_SECONDS = 1.5


def make_engine(url: str) -> Engine:
    """An engine for `url`. SQLite: the file's folder is created, WAL journal so readers do not
    block the runner's writes, and the engine may be used from several threads."""
    parsed = make_url(url)
    if parsed.get_backend_name() == "sqlite":
        if parsed.database and parsed.database != ":memory:":
            Path(parsed.database).parent.mkdir(parents=True, exist_ok=True)
        engine = create_engine(url, connect_args={"check_same_thread": False, "timeout": SQLITE_BUSY_SECONDS})

        @event.listens_for(engine, "connect")
        def _pragmas(conn, _record):
            cur = conn.cursor()
            cur.execute("PRAGMA journal_mode=WAL")
            cur.execute("PRAGMA foreign_keys=ON")
            cur.close()

        return engine
    return create_engine(url, pool_pre_ping=True)


class JobStore:
    def __init__(self, url: str):
        self.url = url
        self.engine = make_engine(url)
        _Base.metadata.create_all(self.engine)
        self._session = sessionmaker(self.engine, expire_on_commit=False)

    def close(self) -> None:
        self.engine.dispose()

    def compact(self) -> None:
        """After an outage: fold SQLite's write-ahead log back into the database file and
        truncate it (a full disk may have left it large). Nothing to do on PostgreSQL."""
        if self.engine.dialect.name == "sqlite":
            with self.engine.connect() as connection:
                connection.exec_driver_sql("PRAGMA wal_checkpoint(TRUNCATE)")

    # --- jobs -------------------------------------------------------------------------------
    def create(self, kind: str, owner: str, spec: dict, plan: dict, total: int) -> Job:
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
            created_at=utcnow(),
            restarts=0,
        )
        with self._session.begin() as s:
            s.add(row)
        return _job(row)

    def get(self, job_id: str) -> Job | None:
        with self._session() as s:
            row = s.get(JobRow, job_id)
            return _job(row) if row is not None else None

    def recent(self, owner: str, limit: int) -> list[tuple[Job, str]]:
        """The owner's newest jobs first, each with its document's name (for a list of them)."""
        with self._session() as s:
            rows = s.scalars(
                select(JobRow).where(JobRow.owner == owner).order_by(JobRow.created_at.desc()).limit(limit)
            )
            return [(_job(r), str(((r.spec or {}).get("document") or {}).get("name", ""))) for r in rows]

    def active(self) -> list[Job]:
        """Jobs queued or running, oldest first."""
        with self._session() as s:
            rows = s.scalars(select(JobRow).where(JobRow.status.in_(ACTIVE)).order_by(JobRow.created_at))
            return [_job(r) for r in rows]

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
        example cancelled while its last task ran): a final status never changes."""
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
        """Store finished points and advance the job's progress in one transaction. Points
        already stored are left as they are (never overwritten). Returns how many were new.
        Which points count as failed is the job kind's to say (`failed`, by default the kind
        of the job asked); the store only counts them."""
        points = list(points)
        if not points:
            return 0
        if failed is None:
            failed = self._kind_of(job_id).failed
        with self._session.begin() as s:
            have = set(
                s.scalars(
                    select(PointRow.index).where(PointRow.job_id == job_id, PointRow.index.in_([i for i, _ in points]))
                )
            )
            now = utcnow()
            new = [(i, d) for i, d in points if i not in have]
            s.add_all(PointRow(job_id=job_id, index=i, data=d, finished_at=now) for i, d in new)
            new_failed = sum(1 for _, d in new if failed(d))
            s.execute(
                update(JobRow)
                .where(JobRow.id == job_id)
                .values(done=JobRow.done + len(new), failed_points=JobRow.failed_points + new_failed)
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
        query = select(PointRow.index, PointRow.data).where(PointRow.job_id == job_id).order_by(PointRow.index)
        if offset:
            query = query.offset(offset)
        if limit is not None:
            query = query.limit(limit)
        with self._session() as s:
            return {i: d for i, d in s.execute(query)}
