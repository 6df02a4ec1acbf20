"""The build queue: compiled kernels are made here, never inside a request.

A request that would run faster compiled asks for a build (request_chain, request_function)
and goes on interpreted; asking writes a small file into <cache>/build-queue/ (and, for a whole
Function, its serialization) and returns. The queue counts in the cache's size bound (the
least recently asked builds are dropped when the cache is over it, models.caches.disk_cache)
and holds at most FLEXMECH_BUILD_QUEUE_MAX builds (over it the oldest is dropped); a dropped
build is logged, and a run that still wants it asks again.

One builder process per server (service.kernels.builder_process) takes the requests oldest first, each into a
folder of its own under <cache>/building/ (outside every evicted section), and compiles each
Function (service.kernels.build: own process group, time and memory limits). A build that fails
or exceeds its limits leaves a note beside where its library would be (abandoned.json) and that
key is not tried again. Whatever goes wrong in one build is that build's failure, logged, and
the builder goes on; a build whose inputs were removed under it (evicted kernels, its
serialized Function, its folder) is dropped without a note, so it can be asked again.

The builder runs in a session of its own, started and watched by the server (BuilderProcess):
a builder that ends is started again after 1, 2, 4 ... 60 s, with its queue kept (the request
it was building goes back once); meanwhile /v1/health says "degraded". Stopping the server
kills the builder's group; a server killed outright takes the builder with it
(PR_SET_PDEATHSIG, and the builder also looks at its parent every second), and the builder
kills its compiler before it exits. `python -m flexmech.service.kernels.queue` is the builder;
`flexmech build` compiles in the foreground without a queue.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import shutil
import signal
import threading
import time
from pathlib import Path

import casadi as ca

from flexmech.models.caches.disk_cache import (
    bound,
    building_dir,
    building_folder,
    cache_dir,
    max_bytes,
    owner_alive,
    queue_dir,
    queue_lock,
    queued,
    touch,
    usage,
)
from flexmech.models.kernels.chain_signature import ChainSignature
from flexmech.models.kernels.chunks import chunks
from flexmech.service.kernels.build import BuildLimits, Compiler, Outcome
from flexmech.service.kernels.cache import KINDS, abandoned, folder, is_compiled, library

log = logging.getLogger("flexmech.kernels")

BUILD_ORDER = ("substitute", "backward", "sweep", "jacobian", "factor")  # the cheap and often-called first
ACCEPTING = "FLEXMECH_BUILD_QUEUE"  # set (to 1) in a server and its workers: requests are written for its builder
QUEUE_MAX = "FLEXMECH_BUILD_QUEUE_MAX"  # builds the queue holds at most (set by the server for its workers)
DEFAULT_QUEUE_MAX = 32
TRIES = 2  # a request its builder ended on this many times is abandoned


def accept_requests(on: bool = True, cap: int | str | None = None) -> None:
    """A server with a builder takes build requests (a CLI run only reads the cache); the
    environment carries it, and the queue's cap, to the job workers the server starts."""
    if on:
        os.environ[ACCEPTING] = "1"
        if cap is not None:
            os.environ[QUEUE_MAX] = str(cap)
    else:
        os.environ.pop(ACCEPTING, None)


def accepting() -> bool:
    return os.environ.get(ACCEPTING) == "1"


def queue_max() -> int:
    try:
        return max(1, int(os.environ.get(QUEUE_MAX) or DEFAULT_QUEUE_MAX))
    except ValueError:
        return DEFAULT_QUEUE_MAX


def trim(cap: int | None = None) -> list[str]:
    """Drop the least recently asked builds while the queue holds more than `cap`
    (FLEXMECH_BUILD_QUEUE_MAX); the names dropped."""
    cap = queue_max() if cap is None else cap
    dropped = []
    with queue_lock():
        waiting = [build for build in queued() if build.request is not None]
        for build in waiting[: max(0, len(waiting) - cap)]:
            build.drop()
            dropped.append(build.name)
            log.warning("build queue holds at most %d builds: dropped %s, the least recently asked", cap, build.name)
    return dropped


def _write_request(key: str, item: dict, staged_function: Path | None = None) -> bool:
    """Queue a request (with its serialized Function, staged beside the queue); False when it
    is queued already (the staged file is then discarded)."""
    path = queue_dir() / f"{key}.json"
    with queue_lock():
        if path.exists():
            if staged_function is not None:
                staged_function.unlink(missing_ok=True)
            return False
        if staged_function is not None:
            os.replace(staged_function, item["serialized"])
        staged = path.with_suffix(f".{os.getpid()}.{threading.get_ident()}.json.tmp")
        staged.write_text(json.dumps(item))
        os.replace(staged, path)
    trim()
    return True


def request_chain(signature: ChainSignature) -> bool:
    """Ask for a chain signature's kernels (no-op when built, abandoned or already asked)."""
    if not accepting() or is_compiled(signature) or abandoned(signature).exists():
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
    from flexmech.service.kernels.cache import version

    digest = hashlib.sha256(f"{key}|{version()}".encode()).hexdigest()[:16]
    return cache_dir() / "libraries" / f"{fn.name()}_{digest}.so"


def request_function(fn: ca.Function, key: str, link: list[str] | None = None) -> bool:
    """Ask for a whole Function compiled (kept at function_library(fn, key)), linked against
    the libraries `link` (which must be there: its serialization names them; asking marks them
    used). The cache is then bounded, the queue included."""
    target = function_library(fn, key)
    if target.exists() or note_of(target).exists() or not accepting():
        return False
    link = list(link or [])
    if any(not Path(path).exists() for path in link):
        return False  # its kernels were evicted: a run asks for them again first
    name = target.stem
    if (queue_dir() / f"{name}.json").exists():
        return False
    for path in link:
        touch(Path(path).parent)
    queue_dir().mkdir(parents=True, exist_ok=True)
    serialized = queue_dir() / f"{name}.casadi"
    staged = serialized.with_suffix(f".{os.getpid()}.{threading.get_ident()}.tmp")
    fn.save(str(staged))
    asked = _write_request(
        name, {"kind": "function", "serialized": str(serialized), "library": str(target), "link": link}, staged
    )
    bound()
    return asked


def note_of(target: Path) -> Path:
    """Beside a whole Function's library: the note that its build was abandoned."""
    return target.with_suffix(".abandoned.json")


# ---- the builder ---------------------------------------------------------------------------
class Gone(Exception):
    """What a build needs was removed under it (evicted, dropped from the queue): the build is
    dropped, not abandoned."""


class Builder:
    def __init__(self, limits: BuildLimits, cap: int | None = None):
        self.limits = limits
        self.cap = cap
        self.compiler = Compiler()

    def pending(self) -> list[Path]:
        """The queue's requests, least recently asked first (over the cap, the oldest dropped)."""
        trim(self.cap)
        return [build.request for build in queued() if build.request is not None]

    def run_one(self, request: Path) -> Outcome | None:
        """Build one request; its outcome, or None when it was dropped (gone from the queue, or
        what it needs removed under it). Whatever goes wrong is this build's failure, logged
        (and noted, unless its inputs were removed): never the builder's."""
        name, claimed, item = request.stem, None, None
        try:
            claimed = self._claim(request)
            if claimed is None:
                return None
            outcome = self._build(claimed[1])
            if outcome.retry:
                raise Gone(outcome.message)
        except Gone as why:
            log.warning("build %s dropped: %s", name, why)
            outcome = None
        except Exception as exc:  # one build's failure of any kind is that build's, never the builder's
            log.exception("build %s failed", name)
            outcome = Outcome(False, f"the build failed: {type(exc).__name__}: {exc}")
            item = claimed[1] if claimed is not None else None
            if claimed is None:  # failed taking it: dropped, or the loop would meet it again at once
                request.unlink(missing_ok=True)
        finally:
            if claimed is not None:
                shutil.rmtree(claimed[0], ignore_errors=True)
        if item is not None:
            self._note(item, outcome)
        try:
            bound()
        except OSError as exc:
            log.warning("cache bound after build %s: %s", name, exc)
        if outcome is not None:
            log.info("build %s: %s (cache %d of %d bytes)", name, outcome.message, usage(), max_bytes())
        return outcome

    def _claim(self, request: Path) -> tuple[Path, dict] | None:
        """Take a request out of the queue into a build folder of its own (its serialized
        Function too): (folder, request), or None when it is gone (dropped, or taken)."""
        with queue_lock():
            if not request.exists():
                return None
            try:
                item = json.loads(request.read_text())
                asked = request.stat().st_mtime
            except (OSError, ValueError) as exc:
                request.unlink(missing_ok=True)
                raise Gone(f"its request cannot be read ({exc})") from exc
            if not isinstance(item, dict):
                request.unlink(missing_ok=True)
                raise Gone("its request is not a JSON object")
            work = building_folder(request.stem)
            try:
                serialized = item.get("serialized")
                taken = {**item, "name": request.stem, "asked": asked}
                if serialized is not None:
                    taken["serialized"] = str(work / "function.casadi")
                (work / "request.json").write_text(json.dumps(taken))
                if serialized is not None:
                    try:
                        os.replace(serialized, work / "function.casadi")
                    except FileNotFoundError:
                        request.unlink(missing_ok=True)
                        raise Gone("its serialized Function is gone (dropped from the queue)") from None
                request.unlink(missing_ok=True)
            except BaseException:
                shutil.rmtree(work, ignore_errors=True)
                raise
        return work, taken

    def _build(self, item: dict) -> Outcome:
        if item.get("kind") == "chain":
            return build_chain(ChainSignature(**item["signature"]), self.compiler, self.limits)
        target, link = Path(item["library"]), list(item.get("link", []))
        _check_links(link)
        for path in link:
            touch(Path(path).parent)  # in use: the newest of the cache
        try:
            fn = ca.Function.load(item["serialized"])
        except RuntimeError:
            _check_links(link)  # a kernel it names evicted meanwhile: dropped, not abandoned
            raise
        outcome = self.compiler.build(fn, target, self.limits, link=link)
        if not outcome.ok and not outcome.retry:
            note_abandoned(note_of(target), outcome)
        return outcome

    def _note(self, item: dict, outcome: Outcome) -> None:
        """Note a failed build where its key is looked up (not tried again)."""
        try:
            if item.get("kind") == "chain":
                note_abandoned(abandoned(ChainSignature(**item["signature"])), outcome)
            else:
                note_abandoned(note_of(Path(item["library"])), outcome)
        except (OSError, TypeError, KeyError, ValueError) as exc:
            log.warning("cannot note the failed build %s: %s", item.get("name"), exc)

    def take_back(self) -> None:
        """At start: remove the build folders of builders that are gone; a request one of them
        was building goes back to the queue, once (a request its builder ended on TRIES times
        is abandoned, noted)."""
        for work in sorted(building_dir().glob("*")) if building_dir().is_dir() else []:
            if owner_alive(work) is not False:
                continue
            try:
                if (work / "request.json").exists():
                    self._requeue(work)
            except (OSError, ValueError, TypeError, KeyError) as exc:
                log.warning("cannot take back the build in %s: %s", work.name, exc)
            shutil.rmtree(work, ignore_errors=True)

    def _requeue(self, work: Path) -> None:
        item = json.loads((work / "request.json").read_text())
        name, asked = item.pop("name"), float(item.pop("asked", time.time()))
        attempts = int(item.get("attempts", 0)) + 1
        if attempts >= TRIES:
            self._note(item, Outcome(False, f"its builder ended {attempts} times while building it"))
            log.warning("build %s abandoned: its builder ended %d times while building it", name, attempts)
            return
        item["attempts"] = attempts
        path = queue_dir() / f"{name}.json"
        with queue_lock():
            if path.exists():  # asked again meanwhile
                return
            if item.get("serialized") is not None:
                serialized = queue_dir() / f"{name}.casadi"
                os.replace(work / "function.casadi", serialized)
                item["serialized"] = str(serialized)
            staged = path.with_suffix(f".{os.getpid()}.tmp")
            staged.write_text(json.dumps(item))
            os.utime(staged, (asked, asked))  # its place in the queue
            os.replace(staged, path)
        log.warning("build %s: back in the queue (its builder ended while building it)", name)

    def serve(self, parent: int) -> None:
        self.take_back()
        while os.getppid() == parent:
            requests = self.pending()
            if not requests:
                time.sleep(0.5)
                continue
            self.run_one(requests[0])


def _check_links(link: list[str]) -> None:
    missing = [path for path in link if not Path(path).exists()]
    if missing:
        raise Gone(f"{len(missing)} of the libraries it links against are gone (evicted), e.g. {missing[0]}")


def build_chain(signature: ChainSignature, compiler: Compiler, limits: BuildLimits, report=None) -> Outcome:
    """Compile a chain signature's chunks, cheapest first; the first failure abandons the key
    (unless its files were removed under it: then it is only reported)."""
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
            if not outcome.retry:
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
    builder = Builder(limits, queue_max())

    def stop(signum, frame):
        builder.compiler.kill()
        os._exit(0)

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    builder.serve(parent)
    builder.compiler.kill()


if __name__ == "__main__":
    main()
