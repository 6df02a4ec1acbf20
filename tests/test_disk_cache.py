"""The disk cache is bounded: over its size, whole entries go, least recently used first, and
using an entry (loading its graphs or kernels) makes it recent."""

from __future__ import annotations

import os

from models.disk_cache import bound, entries, touch


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
