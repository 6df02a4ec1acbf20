"""Retention: jobs are kept FLEXMECH_JOB_RETENTION after they end, then purged.

One thread beside the runner looks every `every` seconds (a quarter of the retention, between
MIN_EVERY and MAX_EVERY) and deletes the expired jobs in batches of PURGE_BATCH, each its own
short transaction, at most MAX_BATCHES per look: the store is never held long, and a backlog
(a server that was down for a month) drains over a few looks. A store that fails is tried at
the next look; a job still queued or running is never purged.
"""

from __future__ import annotations

import logging
import threading
from datetime import timedelta

from sqlalchemy.exc import SQLAlchemyError

from flexmech.service.jobs.store import JobStore, utcnow

log = logging.getLogger("flexmech.retention")

MIN_EVERY, MAX_EVERY = 1.0, 600.0  # seconds between looks
MAX_BATCHES = 10  # batches of one look


def look_interval(retention: timedelta) -> float:
    return min(MAX_EVERY, max(MIN_EVERY, retention.total_seconds() / 4))


class RetentionPurge:
    def __init__(self, store: JobStore, retention: timedelta):
        self.store = store
        self.retention = retention
        self.every = look_interval(retention)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        self._thread = threading.Thread(target=self._loop, name="flexmech-retention", daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 10.0) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)

    def purge_once(self) -> int:
        """Purge the jobs that ended more than the retention ago (up to MAX_BATCHES batches);
        how many went."""
        cutoff = utcnow() - self.retention
        purged = 0
        for _ in range(MAX_BATCHES):
            if self._stop.is_set():
                break
            batch = self.store.purge_ended_before(cutoff)
            purged += batch
            if batch == 0:
                break
        return purged

    def _loop(self) -> None:
        while not self._stop.wait(self.every):
            try:
                purged = self.purge_once()
            except SQLAlchemyError as exc:  # the store is down: the runner's guard reports it; try next look
                log.warning("retention purge skipped: %s", str(exc).splitlines()[0][:300])
                continue
            if purged:
                log.info("retention: purged %d job(s) that ended over %s ago", purged, self.retention)
