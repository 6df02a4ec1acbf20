"""The disk cache (FLEXMECH_CACHE_DIR, else ~/.cache/flexmech): saved graphs, compiled kernels
and libraries, bounded in size by FLEXMECH_CACHE_MAX_BYTES (least recently used evicted).

An entry is one folder or file directly under one of the cache's sections (graphs/<key>,
kernels/<version>/<signature>, libraries/<file>); using it touches it (its modification time
is its last use), and bound() removes whole entries, least recently used first, until the
cache fits. An entry in use by another process is at worst rebuilt: every writer writes to
a temporary name and renames.
"""

from __future__ import annotations

import logging
import os
import shutil
import time
from pathlib import Path

log = logging.getLogger("flexmech.cache")

DEFAULT_MAX_BYTES = 2 * 1024**3
SECTIONS = ("graphs", "kernels", "libraries")


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
    if path.is_file():
        return path.stat().st_size
    total = 0
    for root, _, files in os.walk(path):
        for name in files:
            try:
                total += (Path(root) / name).stat().st_size
            except OSError:
                pass
    return total


def entries() -> list[Path]:
    """Every entry of the cache (versioned kernel folders: their signatures)."""
    root = cache_dir()
    out = []
    for section in SECTIONS:
        base = root / section
        if not base.is_dir():
            continue
        for child in base.iterdir():
            if section == "kernels" and child.is_dir():
                out += [leaf for leaf in child.iterdir()]
            else:
                out.append(child)
    return out


def bound(limit: int | None = None) -> list[Path]:
    """Remove least recently used entries until the cache is at most `limit` bytes
    (FLEXMECH_CACHE_MAX_BYTES); returns what was removed."""
    limit = max_bytes() if limit is None else limit
    sized = []
    for entry in entries():
        try:
            sized.append((entry.stat().st_mtime, entry, _size(entry)))
        except OSError:
            continue
    total = sum(size for _, _, size in sized)
    removed = []
    for _, entry, size in sorted(sized, key=lambda item: item[0]):
        if total <= limit:
            break
        try:
            shutil.rmtree(entry) if entry.is_dir() else entry.unlink()
        except OSError as exc:
            log.warning("cannot remove %s from the cache: %s", entry, exc)
            continue
        total -= size
        removed.append(entry)
    if removed:
        log.info("cache bound %d bytes: removed %d entries", limit, len(removed))
    return removed


def stamp() -> float:
    return time.time()
