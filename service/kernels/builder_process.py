"""The server's kernel builder (service.kernels.queue's main, `python -m flexmech.service.kernels.queue`):
started in a session of its own with the server's lifespan, stopped with its whole group, and
watched: a builder that ends is started again after 1, 2, 4 ... 60 s with its queue kept, and
meanwhile /v1/health says "degraded" (state())."""

from __future__ import annotations

import logging
import os
import signal
import subprocess
import sys
import threading
import time

from flexmech.models.caches.disk_cache import queue_dir
from flexmech.service.kernels.build import die_with_parent
from flexmech.service.kernels.queue import QUEUE_MAX, accept_requests

log = logging.getLogger("flexmech.kernels")


class BuilderProcess:
    """The server's builder: started in a session of its own, stopped with its whole group, and
    watched by a thread that starts it again when it ends (after FIRST_WAIT seconds, doubling
    up to LONGEST_WAIT; a builder up STEADY seconds starts the doubling over)."""

    FIRST_WAIT, LONGEST_WAIT, STEADY = 1.0, 60.0, 60.0
    LOOK_EVERY = 0.5  # seconds between the watcher's looks

    def __init__(self, env: dict[str, str] | None = None):
        self.env = env or {}
        self.proc: subprocess.Popen | None = None
        self.restarts = 0
        self.reason: str | None = None  # why it is not running, while it is not
        self._started = 0.0
        self._lock = threading.Lock()  # start and stop, one at a time
        self._stopping = threading.Event()
        self._watcher: threading.Thread | None = None

    def start(self) -> None:
        self._stopping.clear()
        self._spawn()
        accept_requests(True, self.env.get(QUEUE_MAX))
        self._watcher = threading.Thread(target=self._watch, name="kernel-builder-watcher", daemon=True)
        self._watcher.start()

    def _spawn(self) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "flexmech.service.kernels.queue"],
            env={**os.environ, **self.env},
            start_new_session=True,
            preexec_fn=lambda: (die_with_parent(signal.SIGTERM), os.nice(10)),
        )
        self._started = time.monotonic()

    def _watch(self) -> None:
        """Start the builder again whenever it ends, waiting longer after each quick end. (Its
        builders die with this thread, PR_SET_PDEATHSIG: it runs until stop().)"""
        wait = self.FIRST_WAIT
        while not self._stopping.wait(self.LOOK_EVERY):
            proc = self.proc
            if proc is None or proc.poll() is None:
                if proc is not None and time.monotonic() - self._started > self.STEADY:
                    wait = self.FIRST_WAIT
                continue
            self.reason = f"the builder (pid {proc.pid}) {_how_it_ended(proc.returncode)}; starting again in {wait:g} s"
            log.warning("kernel %s", self.reason)
            if self._stopping.wait(wait):
                return
            with self._lock:
                if self._stopping.is_set():
                    return
                try:
                    self._spawn()
                except OSError as exc:
                    self.reason = f"the builder cannot be started: {exc}"
                    log.warning("kernel %s", self.reason)
                else:
                    self.restarts += 1
                    self.reason = None
                    log.warning("kernel builder started again (pid %d, restart %d)", self.proc.pid, self.restarts)
            wait = min(2 * wait, self.LONGEST_WAIT)

    def queued(self) -> int:
        try:
            return sum(1 for _ in queue_dir().glob("*.json"))
        except OSError:
            return 0

    def running(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def state(self) -> dict[str, int | bool | str | None]:
        """For /v1/health: pid, running, queued, restarts, and while it is down, why. The process
        is read once: the watcher may start a new one meanwhile, and a reason read from that one
        would say a dead builder "is running"."""
        proc = self.proc
        running = proc is not None and proc.poll() is None
        out: dict[str, int | bool | str | None] = {
            "pid": proc.pid if proc is not None else None,
            "running": running,
            "queued": self.queued(),
            "restarts": self.restarts,
        }
        if not running:
            ended = f"the builder (pid {proc.pid}) {_how_it_ended(proc.returncode)}" if proc else "not started"
            out["reason"] = self.reason or f"{ended}; it is started again shortly"
        return out

    @property
    def pid(self) -> int | None:
        return self.proc.pid if self.proc is not None else None

    def stop(self, timeout: float = 5.0) -> None:
        accept_requests(False)
        self._stopping.set()
        with self._lock:
            proc = self.proc
            if proc is not None and proc.poll() is None:
                try:
                    os.killpg(proc.pid, signal.SIGTERM)
                    proc.wait(timeout)
                except subprocess.TimeoutExpired:
                    os.killpg(proc.pid, signal.SIGKILL)
                    proc.wait(timeout)
                except ProcessLookupError:
                    pass
        if self._watcher is not None and self._watcher is not threading.current_thread():
            self._watcher.join(timeout)


def _how_it_ended(code: int | None) -> str:
    if code is None:
        return "is running"
    if code < 0:
        try:
            return f"was killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"was killed by signal {-code}"
    return f"exited with status {code}"
