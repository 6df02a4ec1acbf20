"""Store work that may fail for a while (a locked SQLite file, a full disk, a database that
went away), retried with backoff instead of lost, and logged once a minute, not per attempt."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

from sqlalchemy.exc import SQLAlchemyError

log = logging.getLogger("flexmech.store")

FIRST_DELAY, MAX_DELAY = 0.5, 10.0  # seconds between attempts while the store fails
REPORT_EVERY = 60.0  # seconds between log lines of one outage


class StoreGuard:
    def __init__(self, on_recovery: Callable[[], None] | None = None):
        self.on_recovery = on_recovery
        self._delay = FIRST_DELAY
        self._retry_at = 0.0
        self._down_since: float | None = None
        self._reported = 0.0

    @property
    def down(self) -> bool:
        return self._down_since is not None

    def ready(self) -> bool:
        """Whether it is time to try the store (always, unless it failed a moment ago)."""
        return time.monotonic() >= self._retry_at

    def attempt(self, work: Callable, *args) -> bool:
        """Run store work; False (and a later retry time) when the store failed."""
        try:
            work(*args)
        except SQLAlchemyError as exc:
            self._failed(exc)
            return False
        self._succeeded()
        return True

    def _failed(self, exc: SQLAlchemyError) -> None:
        now = time.monotonic()
        if self._down_since is None:
            self._down_since, self._reported = now, now
            log.warning("job store unavailable, retrying with backoff: %s", str(exc).splitlines()[0][:300])
        elif now - self._reported >= REPORT_EVERY:
            self._reported = now
            log.warning(
                "job store still unavailable after %.0f s: %s", now - self._down_since, str(exc).splitlines()[0][:300]
            )
        self._retry_at = now + self._delay
        self._delay = min(2 * self._delay, MAX_DELAY)

    def _succeeded(self) -> None:
        if self._down_since is not None:
            log.warning("job store back after %.0f s", time.monotonic() - self._down_since)
            self._down_since = None
            if self.on_recovery is not None:
                try:
                    self.on_recovery()
                except SQLAlchemyError as exc:  # housekeeping only: the next write will tell
                    log.warning("after the outage: %s", str(exc).splitlines()[0][:300])
        self._delay = FIRST_DELAY
        self._retry_at = 0.0
