"""The disk cache (FLEXMECH_CACHE_DIR, else ~/.cache/flexmech): saved graphs, compiled kernels
and libraries, the build queue and builds in progress, bounded in size by
FLEXMECH_CACHE_MAX_BYTES.

An entry is one folder or file directly under one of the evicted sections (graphs/<key>,
kernels/<version>/<signature>, libraries/<file>); using it touches it (its modification time
is its last use). A queued build is the files of one name in build-queue/ (<name>.json, the
request, and what it names, e.g. <name>.casadi); its time is when it was asked. bound()
removes whole entries and whole queued builds, the least recent first, until the cache fits;
a queued build goes request first, so no request is left naming a deleted file. Builds in
progress (building/<pid>@<host>-..., their builder's) count but are never removed while their
process lives. An entry in use by another process is at worst rebuilt: every writer writes to
a temporary name and renames.
"""

from __future__ import annotations

import fcntl
import json
import logging
import os
import shutil
import socket
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

log = logging.getLogger("flexmech.cache")

DEFAULT_MAX_BYTES = 2 * 1024**3
SECTIONS = ("graphs", "kernels", "libraries")  # evicted, least recently used first
QUEUE = "build-queue"  # queued builds: counted, the least recently asked dropped
BUILDING = "building"  # builds in progress: counted, removed only once their process is gone
WRITING_SECONDS = 60.0  # a queued file without its request for longer is a writer's leftover


def cache_dir() -> Path:
    root = os.environ.get("FLEXMECH_CACHE_DIR")
    return Path(root) if root else Path.home() / ".cache" / "flexmech"


def max_bytes() -> int:
    value = os.environ.get("FLEXMECH_CACHE_MAX_BYTES")
    try:
        return int(value) if value else DEFAULT_MAX_BYTES
    except ValueError:
        return DEFAULT_MAX_BYTES


def touch(path: Path) -> None:
    """Mark an entry used now."""
    try:
        os.utime(path, None)
    except OSError:
        pass


def _size(path: Path) -> int:
    """Bytes of a file or a folder's files (0 for what vanished meanwhile)."""
    try:
        if not path.is_dir():
            return path.stat().st_size
    except OSError:
        return 0
    total = 0
    for root, _, files in os.walk(path):
        for name in files:
            try:
                total += (Path(root) / name).stat().st_size
            except OSError:
                pass
    return total


def _children(folder: Path) -> list[Path]:
    try:
        return list(folder.iterdir())
    except OSError:  # not there (yet), or removed meanwhile
        return []


def entries() -> list[Path]:
    """Every entry of the evicted sections (versioned kernel folders: their signatures)."""
    root = cache_dir()
    out = []
    for section in SECTIONS:
        for child in _children(root / section):
            if section == "kernels" and child.is_dir():
                out += _children(child)
            else:
                out.append(child)
    return out


# ---- the build queue -------------------------------------------------------------------------
def queue_dir() -> Path:
    return cache_dir() / QUEUE


@contextmanager
def queue_lock() -> Iterator[None]:
    """Held while the queue's requests are added, taken or dropped (by any process): a build is
    never taken half-dropped, nor dropped half-taken."""
    folder = queue_dir()
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / ".lock", "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


@dataclass
class Queued:
    """The files of one name in the queue: its request (when written) and the rest."""

    name: str
    request: Path | None = None
    files: list[Path] = field(default_factory=list)

    def asked(self) -> float:
        """When it was asked (its request's time; else its newest file's); 0 if gone."""
        times = []
        for path in [self.request] if self.request is not None else self.files:
            try:
                times.append(path.stat().st_mtime)
            except OSError:
                pass
        return max(times, default=0.0)

    def size(self) -> int:
        return sum(_size(path) for path in ([self.request] if self.request else []) + self.files)

    def dangling(self) -> bool:
        """A request that names a serialized file which is not there."""
        try:
            named = json.loads(self.request.read_text()).get("serialized") if self.request else None
        except (OSError, ValueError, AttributeError):
            return True
        return named is not None and not Path(named).exists()

    def drop(self) -> None:
        """Remove it, the request first (call with queue_lock held)."""
        for path in ([self.request] if self.request else []) + self.files:
            path.unlink(missing_ok=True)


def queued() -> list[Queued]:
    """The queue's builds, least recently asked first (call with queue_lock held to act on them)."""
    groups: dict[str, Queued] = {}
    for path in _children(queue_dir()):
        if path.name.startswith("."):
            continue
        name = path.name.split(".", 1)[0]
        group = groups.setdefault(name, Queued(name))
        if path.name == f"{name}.json":
            group.request = path
        else:
            group.files.append(path)
    return sorted(groups.values(), key=Queued.asked)


# ---- builds in progress ----------------------------------------------------------------------
def building_dir() -> Path:
    return cache_dir() / BUILDING


def building_folder(label: str = "") -> Path:
    """A new folder for one build of this process, outside every evicted section: bound()
    leaves it alone while this process lives (its name says whose it is)."""
    folder = building_dir()
    folder.mkdir(parents=True, exist_ok=True)
    owner = f"{os.getpid()}@{socket.gethostname()}-{label + '-' if label else ''}"
    return Path(tempfile.mkdtemp(dir=folder, prefix=owner))


def owner_alive(folder: Path) -> bool | None:
    """Whether the process a build folder belongs to lives; None when it cannot be told
    (another host's, or a name not made by building_folder)."""
    pid, _, rest = folder.name.partition("@")
    host = socket.gethostname()
    if not pid.isdigit() or not rest.startswith(host + "-"):
        return None
    try:
        os.kill(int(pid), 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


# ---- the bound -------------------------------------------------------------------------------
def usage() -> int:
    """Bytes the cache holds, as bound() counts them (sections, queue, builds in progress)."""
    root = cache_dir()
    return sum(_size(root / section) for section in (*SECTIONS, QUEUE, BUILDING))


def bound(limit: int | None = None) -> list[Path]:
    """Remove the least recently used entries and the least recently asked queued builds until
    the cache (sections, queue and builds in progress) is at most `limit` bytes
    (FLEXMECH_CACHE_MAX_BYTES); returns what was removed (a queued build: its request)."""
    limit = max_bytes() if limit is None else limit
    removed: list[Path] = []
    pinned = _building_bytes(removed)
    candidates: list[tuple[float, Path | Queued, int]] = []
    for entry in entries():
        try:
            candidates.append((entry.stat().st_mtime, entry, _size(entry)))
        except OSError:
            continue
    if not queue_dir().is_dir():
        return _remove(candidates, pinned, limit, removed)
    with queue_lock():
        now = time.time()
        for build in queued():
            asked, size = build.asked(), build.size()
            if build.request is None and now - asked > WRITING_SECONDS:
                build.drop()
                log.info("cache: removed %s, a queued file without its request", build.name)
            elif build.request is not None and build.dangling():
                build.drop()
                log.warning("cache: dropped the queued build %s: its serialized Function is gone", build.name)
                removed.append(build.request)
            elif build.request is None:  # being written: counted, kept
                pinned += size
            else:
                candidates.append((asked, build, size))
        return _remove(candidates, pinned, limit, removed)


def _building_bytes(removed: list[Path]) -> int:
    """Bytes of builds in progress; a folder whose process is gone is removed unless it holds a
    request its builder was taking (a starting builder puts that back in the queue)."""
    total = 0
    for folder in _children(building_dir()):
        if owner_alive(folder) is False and not (folder / "request.json").exists():
            shutil.rmtree(folder, ignore_errors=True)
            removed.append(folder)
            continue
        total += _size(folder)
    return total


def _remove(candidates, pinned: int, limit: int, removed: list[Path]) -> list[Path]:
    total = pinned + sum(size for _, _, size in candidates)
    evicted = 0
    for used, entry, size in sorted(candidates, key=lambda item: item[0]):
        if total <= limit:
            break
        if isinstance(entry, Queued):
            entry.drop()
            log.warning(
                "cache bound %d bytes: dropped the queued build %s (asked %.0f s ago)",
                limit,
                entry.name,
                time.time() - used,
            )
            removed.append(entry.request)
        else:
            try:
                shutil.rmtree(entry) if entry.is_dir() else entry.unlink()
            except FileNotFoundError:
                pass
            except OSError as exc:
                log.warning("cannot remove %s from the cache: %s", entry, exc)
                continue
            evicted += 1
            removed.append(entry)
        total -= size
    if evicted:
        log.info("cache bound %d bytes: removed %d entries", limit, evicted)
    return removed


def stamp() -> float:
    return time.time()
