"""The job store's tables, its engine, and the columns a store made by an older flexmech lacks.

    flexmech_owners      a row per key, locked while one of its jobs is created (quotas)
    flexmech_documents   each mechanism document once, by the SHA-256 of its JSON text: forty
                         jobs of one document hold one copy
    flexmech_jobs        a job: its spec without the document, the document's digest, and the
                         bytes it holds (spec, plan, points), which quotas count
    flexmech_job_points  each finished point; a large one (an export's archive) is kept
                         zlib-compressed in `packed`, its `data` then empty

SQLite files are made with incremental auto-vacuum, so deleting jobs gives their pages back to
the file system (`PRAGMA incremental_vacuum`), and their write-ahead log is kept to
WAL_LIMIT_BYTES after each checkpoint.
"""

from __future__ import annotations

from datetime import datetime
from pathlib import Path
from typing import Literal

from sqlalchemy import (
    JSON,
    BigInteger,
    DateTime,
    ForeignKey,
    Integer,
    LargeBinary,
    String,
    Text,
    create_engine,
    event,
    inspect,
    text,
)
from sqlalchemy.engine import Engine, make_url
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column

JobStatus = Literal["queued", "running", "succeeded", "failed", "cancelled"]
ACTIVE: tuple[JobStatus, ...] = ("queued", "running")
FINAL: tuple[JobStatus, ...] = ("succeeded", "failed", "cancelled")

# How long a write waits for another writer's lock on an SQLite file before it fails: a
# request then answers 503 with Retry-After at once instead of holding its client, and the
# runner retries its points with backoff (service.jobs.store_guard), so nothing is lost.
SQLITE_BUSY_SECONDS = 1.5
WAL_LIMIT_BYTES = 4 * 2**20  # SQLite's write-ahead log is truncated to this after a checkpoint
NAME_CHARS = 200  # a document's name as listings show it (longer names are abridged)


class Base(DeclarativeBase):
    pass


class OwnerRow(Base):
    """One row per key that made a job: creating a job locks its key's row first, so two
    requests of one key cannot both pass a quota that has room for one."""

    __tablename__ = "flexmech_owners"

    owner: Mapped[str] = mapped_column(String(64), primary_key=True)
    jobs_created: Mapped[int] = mapped_column(BigInteger, default=0)


class DocumentRow(Base):
    __tablename__ = "flexmech_documents"

    digest: Mapped[str] = mapped_column(String(64), primary_key=True)
    body: Mapped[dict] = mapped_column(JSON)
    name: Mapped[str] = mapped_column(String(NAME_CHARS + 3))
    bytes: Mapped[int] = mapped_column(BigInteger)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))


class JobRow(Base):
    __tablename__ = "flexmech_jobs"

    id: Mapped[str] = mapped_column(String(32), primary_key=True)
    kind: Mapped[str] = mapped_column(String(32))
    owner: Mapped[str] = mapped_column(String(64), index=True)
    status: Mapped[str] = mapped_column(String(16), index=True)
    spec: Mapped[dict] = mapped_column(JSON)  # without its document when `document` is set
    plan: Mapped[dict] = mapped_column(JSON)  # the kind's facts about the spec (units, grid)
    total: Mapped[int] = mapped_column(Integer)
    done: Mapped[int] = mapped_column(Integer, default=0)
    failed_points: Mapped[int] = mapped_column(Integer, default=0)
    error: Mapped[str | None] = mapped_column(Text, nullable=True)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    started_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)
    finished_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True, index=True)
    restarts: Mapped[int] = mapped_column(Integer, default=0)
    # None in a job stored before documents were kept apart: its spec holds its document
    document: Mapped[str | None] = mapped_column(
        String(64), ForeignKey("flexmech_documents.digest"), nullable=True, index=True
    )
    bytes: Mapped[int] = mapped_column(BigInteger, default=0)  # spec + plan + points, as stored


class PointRow(Base):
    __tablename__ = "flexmech_job_points"

    job_id: Mapped[str] = mapped_column(
        String(32), ForeignKey("flexmech_jobs.id", ondelete="CASCADE"), primary_key=True
    )
    index: Mapped[int] = mapped_column(Integer, primary_key=True)
    data: Mapped[dict] = mapped_column(JSON)
    finished_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    packed: Mapped[bytes | None] = mapped_column(LargeBinary, nullable=True)


def make_engine(url: str) -> Engine:
    """An engine for `url`. SQLite: the file's folder is created, incremental auto-vacuum (set
    before the first table, so only a new file gets it), WAL journal so readers do not block
    the runner's writes, and the engine may be used from several threads."""
    parsed = make_url(url)
    if parsed.get_backend_name() != "sqlite":
        return create_engine(url, pool_pre_ping=True)
    if parsed.database and parsed.database != ":memory:":
        Path(parsed.database).parent.mkdir(parents=True, exist_ok=True)
    engine = create_engine(url, connect_args={"check_same_thread": False, "timeout": SQLITE_BUSY_SECONDS})

    @event.listens_for(engine, "connect")
    def _pragmas(conn, _record):
        cur = conn.cursor()
        # Setting auto_vacuum takes the write lock, even to its current value: a connection
        # opened while another holds that lock would fail on it, so only a new file is set.
        if cur.execute("PRAGMA page_count").fetchone()[0] == 0:
            cur.execute("PRAGMA auto_vacuum=INCREMENTAL")
        cur.execute("PRAGMA journal_mode=WAL")
        cur.execute(f"PRAGMA journal_size_limit={WAL_LIMIT_BYTES}")
        cur.execute("PRAGMA foreign_keys=ON")
        cur.close()

    return engine


# Columns added since the first store: (table, column, SQL type per dialect, default)
_ADDED = (
    ("flexmech_jobs", "document", {"sqlite": "VARCHAR(64)", "postgresql": "VARCHAR(64)"}, None),
    ("flexmech_jobs", "bytes", {"sqlite": "BIGINT", "postgresql": "BIGINT"}, "0"),
    ("flexmech_job_points", "packed", {"sqlite": "BLOB", "postgresql": "BYTEA"}, None),
)


def create_tables(engine: Engine) -> None:
    """The tables, and in a store an older flexmech made, the columns it lacks; a job stored
    before has its bytes counted once here, so quotas see it."""
    Base.metadata.create_all(engine)
    inspector = inspect(engine)
    missing = [
        (table, column, types, default)
        for table, column, types, default in _ADDED
        if column not in {c["name"] for c in inspector.get_columns(table)}
    ]
    if not missing:
        return
    dialect = engine.dialect.name
    with engine.begin() as connection:
        for table, column, types, default in missing:
            tail = f" NOT NULL DEFAULT {default}" if default is not None else ""
            connection.execute(text(f"ALTER TABLE {table} ADD COLUMN {column} {types[dialect]}{tail}"))
        if any(column == "bytes" for _, column, _, _ in missing):
            connection.execute(text(_COUNT_OLD_BYTES[dialect]))


_AS_TEXT = {"sqlite": "{}", "postgresql": "{}::text"}
_COUNT_OLD_BYTES = {
    dialect: (
        "UPDATE flexmech_jobs SET bytes = "
        f"length({cast.format('spec')}) + length({cast.format('plan')}) + coalesce(("
        f"SELECT sum(length({cast.format('data')})) FROM flexmech_job_points "
        "WHERE flexmech_job_points.job_id = flexmech_jobs.id), 0)"
    )
    for dialect, cast in _AS_TEXT.items()
}
