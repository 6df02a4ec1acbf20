"""The build queue: compiled kernels are made here, never inside a request.

A request that would run faster compiled asks for a build (request_chain, request_function)
and goes on interpreted; asking writes a small file into <cache>/build-queue/ and returns. One
builder process per server (BuilderProcess) takes the requests oldest first and compiles each
Function (service.kernels.build: own process group, time and memory limits). A build that fails
or exceeds its limits leaves a note beside where its library would be (abandoned.json) and
that key is not tried again.

The builder runs in a session of its own, started by the server's lifespan: stopping the
server kills the builder's group; a server killed outright takes the builder with it
(PR_SET_PDEATHSIG, and the builder also looks at its parent every second), and the builder
kills its compiler before it exits. `python -m service.kernels.queue` is the builder;
`flexmech build` compiles in the foreground without a queue.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import casadi as ca

from models.caches.disk_cache import bound, cache_dir
from models.kernels.chain_signature import ChainSignature
from models.kernels.chunks import chunks
from service.kernels.build import BuildLimits, Compiler, Outcome, die_with_parent
from service.kernels.cache import KINDS, abandoned, folder, is_compiled, library

log = logging.getLogger("flexmech.kernels")

BUILD_ORDER = ("substitute", "backward", "sweep", "jacobian", "factor")  # the cheap and often-called first
ACCEPTING = "FLEXMECH_BUILD_QUEUE"  # set (to 1) in a server and its workers: requests are written for its builder


def queue_dir() -> Path:
    return cache_dir() / "build-queue"


def accept_requests(on: bool = True) -> None:
    """A server with a builder takes build requests (a CLI run only reads the cache); the
    environment carries it to the job workers the server starts."""
    if on:
        os.environ[ACCEPTING] = "1"
    else:
        os.environ.pop(ACCEPTING, None)


def accepting() -> bool:
    return os.environ.get(ACCEPTING) == "1"


def _write_request(key: str, item: dict) -> bool:
    if not accepting():
        return False
    path = queue_dir() / f"{key}.json"
    if path.exists():
        return False
    path.parent.mkdir(parents=True, exist_ok=True)
    staged = path.with_suffix(f".{os.getpid()}.{threading.get_ident()}.tmp")
    staged.write_text(json.dumps(item))
    os.replace(staged, path)
    return True


def request_chain(signature: ChainSignature) -> bool:
    """Ask for a chain signature's kernels (no-op when built, abandoned or already asked)."""
    if is_compiled(signature) or abandoned(signature).exists():
        return False
    return _write_request(
        signature.key + "-" + folder(signature).parent.name,
        {
            "kind": "chain",
            "signature": {
                "degree": signature.degree,
                "shear": signature.shear,
                "axial": signature.axial,
                "rule": signature.rule,
            },
        },
    )


def function_library(fn: ca.Function, key: str) -> Path:
    """Where the compiled library of a whole Function (an impact model's chunk) lives."""
    from service.kernels.cache import version

    digest = hashlib.sha256(f"{key}|{version()}".encode()).hexdigest()[:16]
    return cache_dir() / "libraries" / f"{fn.name()}_{digest}.so"


def request_function(fn: ca.Function, key: str, link: list[str] | None = None) -> bool:
    """Ask for a whole Function compiled (kept at function_library(fn, key)), linked against
    the libraries `link`."""
    target = function_library(fn, key)
    if target.exists() or note_of(target).exists() or not accepting():
        return False
    name = target.stem
    serialized = queue_dir() / f"{name}.casadi"
    if (queue_dir() / f"{name}.json").exists():
        return False
    serialized.parent.mkdir(parents=True, exist_ok=True)
    staged = serialized.with_suffix(f".{os.getpid()}.tmp")
    fn.save(str(staged))
    os.replace(staged, serialized)
    return _write_request(
        name, {"kind": "function", "serialized": str(serialized), "library": str(target), "link": list(link or [])}
    )


def note_of(target: Path) -> Path:
    """Beside a whole Function's library: the note that its build was abandoned."""
    return target.with_suffix(".abandoned.json")


# ---- the builder ---------------------------------------------------------------------------
class Builder:
    def __init__(self, limits: BuildLimits):
        self.limits = limits
        self.compiler = Compiler()

    def pending(self) -> list[Path]:
        try:
            requests = [p for p in queue_dir().glob("*.json")]
        except OSError:
            return []
        return sorted(requests, key=lambda p: p.stat().st_mtime if p.exists() else 0.0)

    def run_one(self, request: Path) -> None:
        try:
            item = json.loads(request.read_text())
        except (OSError, ValueError):
            request.unlink(missing_ok=True)
            return
        if item.get("kind") == "chain":
            signature = ChainSignature(**item["signature"])
            outcome = build_chain(signature, self.compiler, self.limits)
        else:
            target = Path(item["library"])
            fn = ca.Function.load(item["serialized"])
            outcome = self.compiler.build(fn, target, self.limits, link=item.get("link", []))
            if not outcome.ok:
                note_abandoned(note_of(target), outcome)
            Path(item["serialized"]).unlink(missing_ok=True)
        log.info("build %s: %s", request.stem, outcome.message)
        request.unlink(missing_ok=True)
        bound()

    def serve(self, parent: int) -> None:
        while os.getppid() == parent:
            requests = self.pending()
            if not requests:
                time.sleep(0.5)
                continue
            self.run_one(requests[0])


def build_chain(signature: ChainSignature, compiler: Compiler, limits: BuildLimits, report=None) -> Outcome:
    """Compile a chain signature's chunks, cheapest first; the first failure abandons the key."""
    functions = chunks(signature).functions()
    total = Outcome(True, "compiled")
    for kind in BUILD_ORDER:
        target = library(signature, kind)
        if target.exists():
            continue
        outcome = compiler.build(functions[kind], target, limits)
        if report is not None:
            report(kind, outcome)
        total.c_bytes += outcome.c_bytes
        total.seconds += outcome.seconds
        total.peak_bytes = max(total.peak_bytes, outcome.peak_bytes)
        if not outcome.ok:
            outcome.message = f"{signature.key} {kind}: {outcome.message}"
            note_abandoned(abandoned(signature), outcome)
            return outcome
    assert set(KINDS) == set(BUILD_ORDER)
    return total


def note_abandoned(path: Path, outcome: Outcome) -> None:
    """Note beside a library that its build failed or exceeded its limits: not tried again."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({**outcome.to_json(), "when": time.time()}))


def main() -> None:
    """The builder process: serve the queue until the parent goes; on SIGTERM, kill the
    compiler and go."""
    logging.basicConfig(level=logging.INFO, format="%(asctime)s builder %(message)s")
    parent = os.getppid()
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    limits = BuildLimits(
        float(os.environ.get("FLEXMECH_BUILD_SECONDS", "60")),
        int(os.environ.get("FLEXMECH_BUILD_MEMORY_BYTES", str(1024**3))),
    )
    builder = Builder(limits)

    def stop(signum, frame):
        builder.compiler.kill()
        os._exit(0)

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    builder.serve(parent)
    builder.compiler.kill()


class BuilderProcess:
    """The server's builder: started in a session of its own, stopped with its whole group."""

    def __init__(self, env: dict[str, str] | None = None):
        self.env = env or {}
        self.proc: subprocess.Popen | None = None

    def start(self) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "service.kernels.queue"],
            env={**os.environ, **self.env},
            start_new_session=True,
            preexec_fn=lambda: (die_with_parent(signal.SIGTERM), os.nice(10)),
        )
        accept_requests(True)

    def queued(self) -> int:
        try:
            return sum(1 for _ in queue_dir().glob("*.json"))
        except OSError:
            return 0

    def running(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    @property
    def pid(self) -> int | None:
        return self.proc.pid if self.proc is not None else None

    def stop(self, timeout: float = 5.0) -> None:
        accept_requests(False)
        if self.proc is None or self.proc.poll() is not None:
            return
        try:
            os.killpg(self.proc.pid, signal.SIGTERM)
            self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait(timeout)
        except ProcessLookupError:
            pass


if __name__ == "__main__":
    main()
