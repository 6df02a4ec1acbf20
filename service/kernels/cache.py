"""Where compiled kernels live and how a run finds them.

A chain signature's five chunks (models.kernels.chunks) are compiled to five shared libraries
in <cache dir>/kernels/<version>/<signature key>/, keyed by the kernels' own sources, the
CasADi version and the compiler flags, never by a structure: every structure with links
of that signature uses them. A signature counts as compiled when all five are there (the
builder installs them atomically, the last one last). A run loads what is there and runs the
rest interpreted; loading touches the folder, which the cache's size bound reads as use
(models.caches.disk_cache).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import threading
from functools import lru_cache
from pathlib import Path

import casadi as ca

from flexmech.models.caches.disk_cache import cache_dir, touch
from flexmech.models.kernels.chain_signature import ChainSignature
from flexmech.models.kernels.chunks import CHUNK, Chunks, chunks

KINDS = ("sweep", "jacobian", "factor", "backward", "substitute")
FLAGS = ("-O2", "-fPIC", "-shared")


def compiler() -> str | None:
    """Path of the C compiler (FLEXMECH_CC, else CC, else gcc), or None."""
    name = os.environ.get("FLEXMECH_CC") or os.environ.get("CC") or "gcc"
    return shutil.which(name)


@lru_cache(maxsize=1)
def version() -> str:
    """A hash of what the kernels' code comes from: their sources, CasADi, the flags, CHUNK (not
    the compiler: an image built with gcc may serve without one, and the C is plain C99)."""
    digest = hashlib.sha256(f"{ca.__version__}|{' '.join(FLAGS)}|{CHUNK}".encode())
    root = Path(__file__).resolve().parents[2] / "models"
    for path in [*sorted((root / "kernels").glob("*.py")), root / "beams" / "link_fe.py"]:
        digest.update(path.read_bytes())
    return digest.hexdigest()[:12]


def folder(signature: ChainSignature) -> Path:
    return cache_dir() / "kernels" / version() / signature.key


def library(signature: ChainSignature, kind: str) -> Path:
    return folder(signature) / f"{kind}.so"


def abandoned(signature: ChainSignature) -> Path:
    """A build that exceeded its limits leaves this note: the key is not tried again."""
    return folder(signature) / "abandoned.json"


def is_compiled(signature: ChainSignature) -> bool:
    return all(library(signature, kind).exists() for kind in KINDS)


_loaded: dict[str, Chunks] = {}
_lock = threading.Lock()


def compiled_for(signatures) -> dict[ChainSignature, Chunks]:
    """The compiled chunks of those signatures that have them (loaded once per process). Loaded
    kernels whose libraries the cache's bound has since removed still run here (their callers
    ask for them again: a window that calls them links against their files)."""
    out = {}
    for signature in signatures:
        key = str(folder(signature))
        with _lock:
            loaded = _loaded.get(key)
            on_disk = is_compiled(signature)
            if loaded is None and on_disk:
                loaded = _load(signature)
                if loaded is not None:
                    _loaded[key] = loaded
        if loaded is not None:
            if on_disk:
                touch(folder(signature))
            out[signature] = loaded
    return out


def _load(signature: ChainSignature) -> Chunks | None:
    interpreted = chunks(signature)
    functions = interpreted.functions()
    try:
        loaded = {kind: ca.external(functions[kind].name(), str(library(signature, kind))) for kind in KINDS}
    except RuntimeError:  # a library that does not load (damaged, another machine's): run interpreted
        return None
    return Chunks(**loaded, factor_size=interpreted.factor_size)
