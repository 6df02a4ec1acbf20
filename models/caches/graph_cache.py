"""Graphs kept in memory and on disk, by structural hash.

Building the graphs of a link structure takes seconds (the shooting integrator unrolled into
SX); loading them serialized takes milliseconds. So the Functions of a structure are saved
under <cache dir>/graphs/<structure key>-<code version>/ (models.caches.disk_cache: bounded in size,
least recently used evicted) when first built, and a new process
(a CLI run, a pool worker, a restarted server) loads the ones it needs. The code version
hashes the sources of the models package and the CasADi version: any change to how graphs
are built makes a new folder. Files are written to a temporary name and renamed, so a
concurrent reader never sees half a file; a file that does not load is rebuilt.

Writing a large structure's graphs takes 0.1-0.45 s (CasADi's serializer), half of what its
first solve takes. A solver worker (api.solver_pool) defers the writing until its answer has
gone out and no other request waits: defer_saves(), then flush_saves(stop) between calls, one
file at a time while stop() is false (a request that arrives meanwhile waits for one file).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path

import casadi as ca

from flexmech.models.caches.disk_cache import bound, cache_dir, touch
from flexmech.models.graph.structure import Structure

log = logging.getLogger("flexmech.graphs")


def code_version() -> str:
    """A hash of the models package's sources, of every registered element family's (one
    registered from elsewhere, a plug-in or a test, is outside the package) and the CasADi
    version."""
    from flexmech.models.elements import FAMILIES

    return _code_version(FAMILIES.sources())


@lru_cache(maxsize=4)
def _code_version(family_sources: tuple[str, ...]) -> str:
    digest = hashlib.sha256(ca.__version__.encode())
    root = Path(__file__).resolve().parents[1]  # every module of models/ (this one is in models/caches/)
    outside = [Path(source) for source in family_sources if not Path(source).resolve().is_relative_to(root)]
    for path in sorted(root.rglob("*.py")):
        digest.update(str(path.relative_to(root)).encode())
        digest.update(path.read_bytes())
    for path in outside:
        digest.update(str(path).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:12]


# per structure, its files' writes waiting for flush_saves(), in order; None: written at once
_deferred: list[list[Callable[[], None]]] | None = None


def defer_saves() -> None:
    """From now on, graphs built in this process are written by flush_saves(), not at once."""
    global _deferred
    if _deferred is None:
        _deferred = []


def flush_saves(stop: Callable[[], bool] = lambda: False) -> None:
    """Write the deferred graphs, one file at a time, until all are written or stop() is true
    (the rest waits for the next call). A structure whose file fails is logged and left: its
    graphs are built again by the next process that needs them."""
    while _deferred and not stop():
        writes = _deferred[0]
        try:
            writes.pop(0)()
        except Exception as exc:  # noqa: BLE001 (CasADi's serializer raises RuntimeError)
            log.warning("cannot save graphs: %s", exc)
            writes.clear()
        if not writes:
            _deferred.pop(0)


def write_atomically(target: Path, write) -> None:
    """write(path) to a temporary name beside target, then rename it into place."""
    staged = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    write(staged)
    os.replace(staged, target)


class GraphStore:
    """The Functions of one structure: from memory, else from disk, else built (and saved)."""

    def __init__(
        self, structure: Structure, build: Callable[[Structure], tuple[dict[str, ca.Function], dict]], kind: str = ""
    ):
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
        writes = self._writes(functions, meta)
        if _deferred is None:
            try:
                for write in writes:
                    write()
            except OSError as exc:  # a read-only home: graphs are rebuilt per process, nothing breaks
                log.warning("cannot save graphs in %s: %s", self.folder, exc)
        else:
            _deferred.append(writes)

    def _writes(self, functions: dict[str, ca.Function], meta: dict) -> list[Callable[[], None]]:
        """The writes that save the graphs, in order: the folder, each Function, then the
        metadata (which marks the folder complete: available()) and the cache's bound."""
        writes = [lambda: self.folder.mkdir(parents=True, exist_ok=True)]
        for name, fn in functions.items():
            writes.append(
                lambda name=name, fn=fn: write_atomically(
                    self.folder / f"{name}.casadi", lambda path: fn.save(str(path))
                )
            )
        text = json.dumps(meta)
        writes.append(lambda: write_atomically(self.folder / "meta.json", lambda path: path.write_text(text)))
        writes.append(bound)
        return writes
