"""Compiled speed without a manual step: a simulation whose kernels are not compiled yet has
them built by `flexmech build` in a child process from its start, on the other core, while it
steps interpreted. Once its first PROBE_SECONDS of stepping say how fast it goes, a run that
would take longer interpreted than the build's rest and its own rest compiled stops and
restarts compiled when the build is done (the progress says so); a shorter run finishes
interpreted, says what compiling gives, and waits for the build, so the next run is compiled.

The build's time is estimated before it starts from the C each part generates (a tenth of a
second to write) at the compile rates measured here (benchmarks.kernel_builds: a chain
signature's kernels 599 kB of factor C in 4.2 s; a window 598-789 kB in 1.3-1.5 s). The child
runs in a process group of its own that ends with the command (Ctrl-C, an error, or the end
waiting for it): no process outlives it.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

PROBE_SECONDS = 0.5  # of interpreted stepping before its pace is trusted
KERNEL_SECONDS_PER_MB = 7.0  # gcc -O2 on a chain signature's kernels (the factor: 599 kB, 4.2 s)
WINDOW_SECONDS_PER_MB = 2.5  # on a window's glue (the rod's 598 kB, 1.3 s; the four-bar's 789 kB, 1.5 s)
COMPILED_SPEEDUP = 2.0  # a run compiled against interpreted, at least (measured: the rod 4.3x, the four-bar 2.3x)
RESTART_SECONDS = 1.0  # what stopping and starting the run again costs (its start, its first window)


@dataclass(frozen=True)
class Missing:
    """What a document's runs would compile that is not there: names and estimated seconds."""

    parts: tuple[str, ...]
    seconds: float


def missing_kernels(mech) -> Missing:
    """The document's kernels (and, with them, its window) not compiled yet, nor abandoned."""
    import casadi as ca

    from flexmech.service.kernels.cache import compiler
    from flexmech.service.kernels.needs import builds_of

    if compiler() is None:
        return Missing((), 0.0)
    parts, seconds = [], 0.0
    with tempfile.TemporaryDirectory(prefix="flexmech-estimate-") as folder:
        for build in builds_of(mech):
            if build.built or build.note.exists():
                continue
            for part, fn, target in build.functions:
                if target.exists():
                    continue
                generator = ca.CodeGenerator(f"{fn.name()}.c", {"with_header": False})
                generator.add(fn)
                size = Path(generator.generate(folder + os.sep)).stat().st_size
                parts.append(f"{build.name} {part}")
                seconds += size / 1e6 * KERNEL_SECONDS_PER_MB
        if parts:
            seconds += WINDOW_SECONDS_PER_MB * 0.8  # its window, once the kernels are there: about 0.8 MB
    return Missing(tuple(parts), seconds)


class KernelBuild:
    """`flexmech build DOCUMENT` in a child process group that ends with this process."""

    def __init__(self, document: Path, estimate: float):
        self.document, self.estimate = document, estimate
        self.started = time.monotonic()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "flexmech.api.cli", "build", str(document)],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
            preexec_fn=_ends_with_parent,
        )

    def done(self) -> bool:
        return self.proc.poll() is not None

    def left(self) -> float:
        """Seconds the build is estimated to take still."""
        return 0.0 if self.done() else max(self.estimate - (time.monotonic() - self.started), 0.5)

    def wait(self) -> bool:
        """Wait for it; whether it built everything."""
        return self.proc.wait() == 0

    def end(self) -> None:
        """Kill it and its compilers now (an interrupted command). A compiler runs in a process
        group of its own (service.kernels.build), which killing the build's would not reach: the
        build is stopped first (it starts no other), then every group below it is killed."""
        if self.done():
            return
        _signal_group(self.proc.pid, signal.SIGSTOP)
        for group in _groups(_descendants(self.proc.pid)) - {self.proc.pid}:
            _signal_group(group, signal.SIGKILL)
        _signal_group(self.proc.pid, signal.SIGKILL)
        self.proc.wait()


def _signal_group(group: int, sig: int) -> None:
    try:
        os.killpg(group, sig)
    except ProcessLookupError:  # it ended meanwhile
        pass


def _groups(pids: list[int]) -> set[int]:
    found = set()
    for pid in pids:
        try:
            found.add(os.getpgid(pid))
        except ProcessLookupError:
            pass
    return found


def _descendants(pid: int) -> list[int]:
    """The processes below `pid` (Linux: /proc)."""
    children: dict[int, list[int]] = {}
    for entry in filter(str.isdigit, os.listdir("/proc")):
        try:
            parent = int(Path(f"/proc/{entry}/stat").read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            continue
        children.setdefault(parent, []).append(int(entry))
    found, stack = [], [pid]
    while stack:
        for child in children.get(stack.pop(), []):
            found.append(child)
            stack.append(child)
    return found


def _ends_with_parent() -> None:
    from flexmech.service.kernels.build import die_with_parent

    die_with_parent()


class Pace:
    """The stop callback of an interpreted run: true once its pace says that stopping, waiting
    for the build and stepping the rest compiled ends sooner than stepping on interpreted. The
    pace is measured from its first window on (the first includes making the run's Functions)."""

    def __init__(self, until: float, build: KernelBuild):
        self.until, self.build = until, build
        self.first: tuple[float, float] | None = None  # (t, when) of the first window's end
        self.t, self.now = 0.0, 0.0
        self.restart = False

    def heard(self, t: float, steps: int | None = None) -> None:
        self.t, self.now = t, time.monotonic()
        if self.first is None:
            self.first = (t, self.now)

    def __call__(self) -> bool:
        if self.first is None or self.now - self.first[1] < PROBE_SECONDS or self.t <= self.first[0]:
            return False
        per_second = (self.now - self.first[1]) / (self.t - self.first[0])  # wall per simulated second
        interpreted = (self.until - self.t) * per_second
        compiled = self.until * per_second / COMPILED_SPEEDUP + RESTART_SECONDS
        self.restart = interpreted > self.build.left() + compiled
        return self.restart
