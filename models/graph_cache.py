"""Graphs kept in memory and on disk, by structural hash.

Building the graphs of a link structure takes seconds (the shooting integrator unrolled into
SX); loading them serialized takes milliseconds. So the Functions of a structure are saved
under <cache dir>/graphs/<structure key>-<code version>/ (models.disk_cache: bounded in size,
least recently used evicted) when first built, and a new process
(a CLI run, a pool worker, a restarted server) loads the ones it needs. The code version
hashes the sources of the models package and the CasADi version: any change to how graphs
are built makes a new folder. Files are written to a temporary name and renamed, so a
concurrent reader never sees half a file; a file that does not load is rebuilt.

Writing a large structure's graphs takes 0.3-0.45 s (CasADi's serializer), most of what its
first solve has left after building them. A solver worker (api.solver_pool) defers the
writing until its answer has gone out: defer_saves(), then flush_saves() between calls.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
from functools import lru_cache
from pathlib import Path
from typing import Callable

import casadi as ca

from models.disk_cache import bound, cache_dir, touch
from models.structure import Structure

log = logging.getLogger("flexmech.graphs")


@lru_cache(maxsize=1)
def code_version() -> str:
    """A hash of the models package's sources and the CasADi version."""
    digest = hashlib.sha256(ca.__version__.encode())
    root = Path(__file__).resolve().parent
    for path in sorted(root.rglob("*.py")):
        digest.update(str(path.relative_to(root)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:12]


_deferred: list[Callable[[], None]] | None = None  # saves waiting for flush_saves(); None: save at once


def defer_saves() -> None:
    """From now on, graphs built in this process are written by flush_saves(), not at once."""
    global _deferred
    if _deferred is None:
        _deferred = []


def flush_saves() -> None:
    """Write the graphs whose saving was deferred (a save that fails is logged: the graphs are
    built again by the next process that needs them)."""
    while _deferred:
        save = _deferred.pop(0)
        try:
            save()
        except Exception as exc:  # noqa: BLE001 (CasADi's serializer raises RuntimeError)
            log.warning("cannot save graphs: %s", exc)


def write_atomically(target: Path, write) -> None:
    """write(path) to a temporary name beside target, then rename it into place."""
    staged = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    write(staged)
    os.replace(staged, target)


class GraphStore:
    """The Functions of one structure: from memory, else from disk, else built (and saved)."""

    def __init__(self, structure: Structure, build: Callable[[Structure], tuple[dict[str, ca.Function], dict]],
                 kind: str = ""):
        self.structure = structure
        self.build = build  # structure -> (Functions by name, their metadata)
        suffix = f"-{kind}" if kind else ""  # a store of a part of the Functions (its own build) has its own folder
        self.folder = cache_dir() / "graphs" / f"{structure.key}-{code_version()}{suffix}"
        self._functions: dict[str, ca.Function] = {}
        self._meta: dict | None = None

    @property
    def meta(self) -> dict:
        if self._meta is None:
            self._meta = self._load_meta()
            if self._meta is None:
                self._build()
        return self._meta

    def available(self) -> bool:
        """Built in this process or saved: its Functions load without building."""
        return self._meta is not None or (self.folder / "meta.json").exists()

    def function(self, name: str) -> ca.Function:
        if name not in self._functions:
            self.meta  # noqa: B018  (on a miss this builds, and so holds, every Function)
        if name not in self._functions:
            loaded = self._load(name)
            if loaded is None:
                self._build()
            else:
                self._functions[name] = loaded
        return self._functions[name]

    def _load_meta(self) -> dict | None:
        try:
            meta = json.loads((self.folder / "meta.json").read_text())
        except (OSError, ValueError):
            return None
        touch(self.folder)  # used now: the cache's bound evicts the least recently used
        return meta

    def _load(self, name: str) -> ca.Function | None:
        path = self.folder / f"{name}.casadi"
        if not path.exists():
            return None
        try:
            return ca.Function.load(str(path))
        except RuntimeError:  # a damaged file: rebuild rather than fail
            log.warning("cannot load %s: rebuilding the graphs", path)
            return None

    def _build(self) -> None:
        functions, meta = self.build(self.structure)
        self._functions.update(functions)
        self._meta = meta
        if _deferred is None:
            self._save(functions, meta)
        else:
            _deferred.append(lambda: self._save(functions, meta))

    def _save(self, functions: dict[str, ca.Function], meta: dict) -> None:
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            for name, fn in functions.items():
                write_atomically(self.folder / f"{name}.casadi", lambda path, fn=fn: fn.save(str(path)))
            write_atomically(self.folder / "meta.json", lambda path: path.write_text(json.dumps(meta)))
            bound()
        except OSError as exc:  # a read-only home: graphs are rebuilt per process, nothing breaks
            log.warning("cannot save graphs in %s: %s", self.folder, exc)
