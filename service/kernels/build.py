"""Compiling one CasADi Function to a shared library, under a time and a memory limit.

The C is generated in this process (CasADi's code generator: small for kernels, a second at
most); the compiler runs as a child in a process group of its own, limited in address space
(RLIMIT_AS, which its own children, cc1 and as, inherit) and in CPU time (so that even a
compiler orphaned by a crash cannot run long), niced, and sent SIGKILL with its whole group at
the wall-time limit. It also dies with this process (PR_SET_PDEATHSIG). The C, the log and the
library are made in a folder of the build's own under <cache>/building/, outside every section
the cache's size bound evicts (models.caches.disk_cache), and the library is installed by an
atomic rename: a reader never loads half a file.

A build that fails or exceeds its limits is reported as an Outcome with the reason; the
caller (service.kernels.queue) notes it and does not try that key again, unless the failure
came from files removed under the build (its folder, a library it links against: `retry`).
"""

from __future__ import annotations

import ctypes
import errno
import os
import resource
import shutil
import signal
import subprocess
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import casadi as ca

from flexmech.models.caches.disk_cache import building_folder
from flexmech.service.kernels.cache import FLAGS, compiler

PR_SET_PDEATHSIG = 1
# how gcc ends when its address-space limit refuses memory, depending on where it asked: an
# allocation's message, cc1 crashing (a stack or mmap it could not get), or the loader unable to
# map cc1's libraries at all
OUT_OF_MEMORY = (
    "out of memory",
    "virtual memory exhausted",
    "Cannot allocate",
    "signal terminated program",
    "failed to map segment from shared object",
)


@dataclass(frozen=True)
class BuildLimits:
    seconds: float = 60.0  # wall time of one compiler run
    memory_bytes: int = 1024**3  # address space of each compiler process


@dataclass
class Outcome:
    ok: bool
    message: str
    c_bytes: int = 0
    seconds: float = 0.0  # compiler wall time
    peak_bytes: int = 0  # the compiler's largest resident set (cc1 included)
    retry: bool = False  # failed because files were removed under the build: not the Function's fault

    def to_json(self) -> dict:
        return asdict(self)


def die_with_parent(sig: int = signal.SIGKILL) -> None:
    """In a child between fork and exec: receive `sig` when the parent dies (Linux)."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, int(sig), 0, 0, 0)
    except (OSError, AttributeError):  # not Linux: the CPU limit still bounds an orphan
        pass


def _missing(link) -> list[str]:
    return [path for path in link if not os.path.exists(path)]


def _install(partial: Path, target: Path) -> None:
    """Move a built library to its place at once (its folder made again if the cache's bound
    removed it meanwhile; across file systems, copied beside it first)."""
    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        os.replace(partial, target)
    except OSError as exc:
        if exc.errno != errno.EXDEV:
            raise
        staged = target.with_name(f".{target.name}.{os.getpid()}.tmp")
        shutil.copyfile(partial, staged)
        os.replace(staged, target)


def _limited(limits: BuildLimits):
    cpu = int(limits.seconds) + 5

    def setup() -> None:
        die_with_parent()
        resource.setrlimit(resource.RLIMIT_AS, (limits.memory_bytes, limits.memory_bytes))
        resource.setrlimit(resource.RLIMIT_CPU, (cpu, cpu + 5))
        os.nice(10)

    return setup


class Compiler:
    """Runs compilers one at a time; kill() ends the one running (and its children) now."""

    def __init__(self):
        self.running: int | None = None  # the process group of the compiler now running

    def kill(self) -> None:
        group = self.running
        if group is not None:
            try:
                os.killpg(group, signal.SIGKILL)
            except ProcessLookupError:
                pass

    def build(
        self, fn: ca.Function, target: Path, limits: BuildLimits = BuildLimits(), link: list[str] | tuple[str, ...] = ()
    ) -> Outcome:
        """Generate fn's C and compile it to `target` (installed atomically), linked against the
        libraries `link` (the compiled kernels a window calls). Whatever fails is the Outcome's
        reason, never an exception: with `retry` when the build's folder or a library it links
        against was removed under it."""
        cc = compiler()
        if cc is None:
            return Outcome(False, "no C compiler (set FLEXMECH_CC or CC, or install gcc)")
        if _missing(link):
            return Outcome(False, f"a library it links against is gone: {_missing(link)[0]}", retry=True)
        try:
            work = building_folder(fn.name())
        except OSError as exc:
            return Outcome(False, f"no build folder: {exc}")
        try:
            return self._build_in(work, cc, fn, target, limits, link)
        except (OSError, RuntimeError) as exc:  # RuntimeError: CasADi's code generator writing the C
            removed = isinstance(exc, FileNotFoundError) or not work.is_dir() or bool(_missing(link))
            why = "files it needs were removed during the build" if removed else "the build failed"
            return Outcome(False, f"{why}: {type(exc).__name__}: {exc}", retry=removed)
        finally:
            shutil.rmtree(work, ignore_errors=True)

    def _build_in(self, work: Path, cc: str, fn: ca.Function, target: Path, limits: BuildLimits, link) -> Outcome:
        generator = ca.CodeGenerator(f"{fn.name()}.c", {"with_header": False})
        generator.add(fn)
        source = Path(generator.generate(str(work) + os.sep))
        c_bytes = source.stat().st_size
        partial = work / "library.so"
        outcome = self._run([cc, *FLAGS, str(source), *link, "-o", str(partial), "-lm"], limits, work / "log")
        outcome.c_bytes = c_bytes
        if outcome.ok:
            _install(partial, target)
        elif not work.is_dir() or _missing(link):
            outcome.message = f"files it needs were removed during the build: {outcome.message}"
            outcome.retry = True
        return outcome

    def _run(self, command: list[str], limits: BuildLimits, log: Path) -> Outcome:
        started = time.monotonic()
        with open(log, "wb") as out:
            proc = subprocess.Popen(
                command, stdout=out, stderr=subprocess.STDOUT, process_group=0, preexec_fn=_limited(limits)
            )
        self.running = proc.pid
        status, usage, timed_out = None, None, False
        try:
            while True:
                done, status, usage = os.wait4(proc.pid, os.WNOHANG)
                if done:
                    break
                if time.monotonic() - started > limits.seconds:
                    timed_out = True
                    self.kill()
                    _, status, usage = os.wait4(proc.pid, 0)
                    break
                time.sleep(0.02)
        finally:
            self.running = None
            proc.returncode = 0  # reaped by wait4: Popen must not wait again
        seconds = time.monotonic() - started
        peak = usage.ru_maxrss * 1024 if usage is not None else 0
        if timed_out:
            return Outcome(False, f"the compiler exceeded its time limit of {limits.seconds:g} s", 0, seconds, peak)
        mib = f"{limits.memory_bytes / 2**20:.0f} MiB"
        if os.WIFSIGNALED(status):
            why = signal.Signals(os.WTERMSIG(status)).name
            return Outcome(
                False,
                f"the compiler was killed by {why}: its memory limit of {mib} or its CPU time ran out",
                0,
                seconds,
                peak,
            )
        if os.WEXITSTATUS(status) != 0:
            text = log.read_text(errors="replace")[-2000:]
            reason = (
                f"the compiler ran out of its memory limit of {mib}"
                if any(sign in text for sign in OUT_OF_MEMORY)
                else f"the compiler failed (exit {os.WEXITSTATUS(status)}): {text.strip()[-400:]}"
            )
            return Outcome(False, reason, 0, seconds, peak)
        return Outcome(True, "compiled", 0, seconds, peak)
