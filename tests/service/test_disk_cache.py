"""The disk cache is bounded: over its size, whole entries go, least recently used first, and
using an entry (loading its graphs or kernels) makes it recent. A solver worker writes a new
structure's graphs after its answer."""

from __future__ import annotations

import json
import os
import socket

import numpy as np
from conftest import EXAMPLES

from flexmech.models import compile_mechanism, load_document
from flexmech.models.caches import graph_cache
from flexmech.models.caches.disk_cache import bound, building_folder, entries, queue_dir, touch, usage
from flexmech.models.caches.graph_cache import GraphStore
from flexmech.models.graph.assembly import FUNCTIONS, build_functions


def _entry(root, section: str, name: str, size: int, used: float):
    path = root / section / name
    path.mkdir(parents=True)
    (path / "data.bin").write_bytes(b"x" * size)
    os.utime(path, (used, used))
    return path


def test_the_least_recently_used_entries_go_until_the_cache_fits(tmp_path, monkeypatch):
    monkeypatch.setenv("FLEXMECH_CACHE_DIR", str(tmp_path))
    old = _entry(tmp_path, "graphs", "old", 4000, 1_000)
    middle = _entry(tmp_path, "kernels/v1", "chain_a", 4000, 2_000)
    new = _entry(tmp_path, "graphs", "new", 4000, 3_000)
    assert set(entries()) == {old, middle, new}
    assert bound(9000) == [old]
    assert not old.exists() and middle.exists() and new.exists()
    touch(middle)  # used now: the graphs entry is now the oldest
    assert bound(5000) == [new]
    assert middle.exists()


def test_the_bound_is_a_setting(tmp_path, monkeypatch):
    monkeypatch.setenv("FLEXMECH_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("FLEXMECH_CACHE_MAX_BYTES", "5000")
    kept = _entry(tmp_path, "libraries", "b", 3000, 2_000)
    gone = _entry(tmp_path, "libraries", "a", 3000, 1_000)
    assert bound() == [gone] and kept.exists()


def _queued(name: str, size: int, asked: float, serialized: bool = True) -> None:
    """A queued build as service.kernels.queue writes one: its serialized Function, then its request."""
    queue_dir().mkdir(parents=True, exist_ok=True)
    item = {"kind": "function", "library": f"/nowhere/{name}.so"}
    if serialized:
        (queue_dir() / f"{name}.casadi").write_bytes(b"x" * size)
        item["serialized"] = str(queue_dir() / f"{name}.casadi")
    (queue_dir() / f"{name}.json").write_text(json.dumps(item))
    os.utime(queue_dir() / f"{name}.json", (asked, asked))


def test_the_queue_and_builds_in_progress_count_and_the_least_recently_asked_build_goes_whole(tmp_path, monkeypatch):
    """The queue is bounded with the sections (a queued build by when it was asked, its request
    and serialized Function together); a build in progress counts but stays; a dead process's
    build folder goes; a request naming a file that is gone goes at once."""
    monkeypatch.setenv("FLEXMECH_CACHE_DIR", str(tmp_path))
    library = _entry(tmp_path, "libraries", "old.so", 3000, 1_000)
    _queued("asked_first", 4000, 2_000)
    _queued("asked_last", 4000, 4_000)
    kernels = _entry(tmp_path, "kernels/v1", "chain_a", 3000, 3_000)
    _queued("dangling", 10, 5_000)
    (queue_dir() / "dangling.casadi").unlink()
    working = building_folder("window")
    (working / "window.c").write_bytes(b"x" * 5000)
    dead = tmp_path / "building" / f"999999999@{socket.gethostname()}-window-x"
    dead.mkdir()
    (dead / "window.c").write_bytes(b"x" * 5000)
    removed = bound(13_000)  # 3000 + 4000 + 4000 + 3000 + 5000 in progress: the library and the first asked go
    assert set(removed) == {library, queue_dir() / "asked_first.json", queue_dir() / "dangling.json", dead}
    assert sorted(p.name for p in queue_dir().iterdir() if not p.name.startswith(".")) == [
        "asked_last.casadi",
        "asked_last.json",
    ]
    assert kernels.exists() and (working / "window.c").exists()
    assert usage() == 4000 + 3000 + 5000 + len((queue_dir() / "asked_last.json").read_bytes())
    assert bound(1000) and (working / "window.c").exists()  # never a live process's build


def test_deferred_graphs_are_written_at_the_flush_and_then_loaded(tmp_path, monkeypatch):
    """A solver worker defers writing a new structure's graphs until its answer has gone out
    (models.caches.graph_cache.defer_saves): nothing is on disk before the flush, everything after,
    and another store (another process) loads them instead of building."""
    monkeypatch.setenv("FLEXMECH_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(graph_cache, "_deferred", None)  # restored after the test: saving at once
    graph_cache.defer_saves()
    mech = compile_mechanism(load_document(EXAMPLES / "cantilever.json"))
    built = GraphStore(mech.structure, build_functions)
    residual = built.function("residual")
    assert not list(tmp_path.rglob("*.casadi"))
    graph_cache.flush_saves()
    (meta,) = tmp_path.glob("graphs/*/meta.json")
    assert (meta.parent / "residual_and_tangent.casadi").exists()

    def build_again(structure):
        raise AssertionError("the saved graphs were built again")

    loaded = GraphStore(mech.structure, build_again).function("residual")
    z = np.linspace(0.0, 0.01, residual.size1_in(0))
    np.testing.assert_array_equal(np.asarray(loaded(z, mech.p())), np.asarray(residual(z, mech.p())))


def test_a_flush_stops_between_files_when_told_and_goes_on_later(tmp_path, monkeypatch):
    """A worker flushes while no request waits (flush_saves(stop)): it stops between two files
    when stop() is true, the structure then has no metadata (not available: another process
    builds rather than load half of it), and the next flush writes the rest."""
    monkeypatch.setenv("FLEXMECH_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(graph_cache, "_deferred", None)
    graph_cache.defer_saves()
    mech = compile_mechanism(load_document(EXAMPLES / "cantilever.json"))
    store = GraphStore(mech.structure, build_functions)
    store.function("residual")
    calls = []

    def stop_after_three_files():
        calls.append(1)
        return len(calls) > 4  # the folder, then three files

    graph_cache.flush_saves(stop=stop_after_three_files)
    assert len(list(tmp_path.rglob("*.casadi"))) == 3
    assert not list(tmp_path.rglob("meta.json")) and not GraphStore(mech.structure, build_functions).available()
    graph_cache.flush_saves()
    assert len(list(tmp_path.rglob("*.casadi"))) == len(FUNCTIONS)
    assert GraphStore(mech.structure, build_functions).available()
    assert graph_cache._deferred == []
