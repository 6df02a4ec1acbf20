"""What the job store holds and how it lets go of it: usage against quotas, deleting a job,
purging jobs past their retention, and giving the freed pages back (SQLite)."""

from __future__ import annotations

import logging
from datetime import datetime
from pathlib import Path

from sqlalchemy import delete, func, select, text
from sqlalchemy.engine import Engine, make_url
from sqlalchemy.exc import SQLAlchemyError
from sqlalchemy.orm import sessionmaker

from flexmech.service.jobs.quotas import Usage
from flexmech.service.jobs.store_accounting import drop_unused_documents, job_counts, owner_uses_document, usage_of
from flexmech.service.jobs.store_schema import FINAL, DocumentRow, JobRow, PointRow

log = logging.getLogger("flexmech.store")

PURGE_BATCH = 200  # jobs deleted per transaction of a purge: a purge never holds the store long


class StoreHousekeeping:
    engine: Engine
    url: str
    _session: sessionmaker

    def usage(self, owner: str) -> Usage:
        with self._session() as s:
            return usage_of(s, owner)

    def totals(self) -> dict:
        """The whole store: jobs, those queued or running, documents, the bytes they hold (as
        quotas count them) and the database's own size on disk (pages, indexes, log)."""
        with self._session() as s:
            jobs, running, job_bytes = job_counts(s)
            documents, document_bytes = s.execute(
                select(func.count(DocumentRow.digest), func.coalesce(func.sum(DocumentRow.bytes), 0))
            ).one()
        return {
            "jobs": jobs,
            "running": running,
            "documents": int(documents),
            "bytes": job_bytes + int(document_bytes),
            "database_bytes": self.database_bytes(),
        }

    def database_bytes(self) -> int | None:
        """The database's size: SQLite's file and its write-ahead log; PostgreSQL's database."""
        if self.engine.dialect.name == "sqlite":
            path = make_url(self.url).database
            if not path or path == ":memory:":
                return None
            return sum(p.stat().st_size for p in (Path(path), Path(path + "-wal")) if p.exists())
        with self.engine.connect() as connection:
            return int(connection.execute(text("SELECT pg_database_size(current_database())")).scalar_one())

    def delete(self, job_id: str) -> int | None:
        """Delete a job with its points (and its document, when no other job uses it); the
        bytes its owner gets back, None when there was no such job."""
        with self._session.begin() as s:
            row = s.get(JobRow, job_id)
            if row is None:
                return None
            owner, digest, freed = row.owner, row.document, row.bytes
            _delete_jobs(s, [job_id])
            if digest is not None and not owner_uses_document(s, owner, digest):
                freed += s.scalar(select(DocumentRow.bytes).where(DocumentRow.digest == digest)) or 0
            drop_unused_documents(s, {digest} if digest else set())
        self.vacuum()
        return freed

    def purge_ended_before(self, cutoff: datetime, batch: int = PURGE_BATCH) -> int:
        """Delete up to `batch` jobs that ended before `cutoff` (oldest first), as delete()
        does; how many. A job still queued or running is never purged."""
        with self._session.begin() as s:
            ids = list(
                s.scalars(
                    select(JobRow.id)
                    .where(JobRow.status.in_(FINAL), JobRow.finished_at < cutoff)
                    .order_by(JobRow.finished_at)
                    .limit(batch)
                )
            )
            if not ids:
                return 0
            digests = set(s.scalars(select(JobRow.document).where(JobRow.id.in_(ids), JobRow.document.is_not(None))))
            _delete_jobs(s, ids)
            drop_unused_documents(s, digests)
        self.vacuum()
        return len(ids)

    def vacuum(self) -> None:
        """SQLite: hand the pages deleted rows left free back to the file system (a file made
        with incremental auto-vacuum; an older file reuses them for new rows instead)."""
        if self.engine.dialect.name != "sqlite":
            return
        try:
            with self.engine.connect() as connection:
                connection.exec_driver_sql("PRAGMA incremental_vacuum")
                connection.exec_driver_sql("PRAGMA wal_checkpoint(PASSIVE)")
                connection.commit()
        except SQLAlchemyError as exc:  # housekeeping only: the rows are gone, their pages go next time
            log.warning("could not give freed pages back yet: %s", str(exc).splitlines()[0][:300])

    def compact(self) -> None:
        """After an outage: fold SQLite's write-ahead log back into the database file and
        truncate it (a full disk may have left it large). Nothing to do on PostgreSQL."""
        if self.engine.dialect.name == "sqlite":
            with self.engine.connect() as connection:
                connection.exec_driver_sql("PRAGMA wal_checkpoint(TRUNCATE)")


def _delete_jobs(s, ids: list[str]) -> None:
    """The jobs and their points (their documents are the caller's to drop once unused)."""
    s.execute(delete(PointRow).where(PointRow.job_id.in_(ids)))
    s.execute(delete(JobRow).where(JobRow.id.in_(ids)))
