"""Compiled windows: a structure's window of time steps (service.dynamics.engine) generated as C
that calls its compiled chain kernels by name and links against their libraries (it never
inlines them): about 1 MB of glue for the rod or the four-bar, 5-7 s of gcc, after which a
window runs without CasADi's virtual machine between its kernels (the rod's step 2.5x faster
than the same kernels with interpreted glue).

A window is keyed by the Function itself (a hash of its serialization, which names its kernels'
libraries): a renamed structure has the same graph, so the same library. It is built by the
build queue once its kernels are there (or by `flexmech build`); until then, and wherever its
build was abandoned, the window runs with its glue interpreted."""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict

import casadi as ca

from flexmech.models.caches.disk_cache import touch
from flexmech.models.kernels.chain_signature import ChainSignature
from flexmech.service.kernels.cache import KINDS, library
from flexmech.service.kernels.queue import function_library, request_function

LOADED = 32  # compiled windows kept loaded per process (one per structure and window length)
_loaded: OrderedDict[str, ca.Function] = OrderedDict()
_lock = threading.Lock()


def window_key(fn: ca.Function) -> str:
    """The window's content key: a hash of its serialized graph (about 4 MB for the four-bar,
    hashed in a few tens of ms: callers keep it)."""
    return hashlib.sha256(fn.serialize().encode()).hexdigest()[:24]


def links(signatures) -> list[str]:
    """The kernel libraries a window of these chain signatures calls."""
    return [str(library(signature, kind)) for signature in signatures for kind in KINDS]


def compiled_window(fn: ca.Function, key: str, signatures: list[ChainSignature]) -> ca.Function | None:
    """The compiled window of fn (key: window_key(fn)) where its library is built, loaded once
    per process; else None, and a server's build queue is asked for it."""
    target = function_library(fn, key)
    with _lock:
        loaded = _loaded.get(str(target))
        if loaded is None and target.exists():
            try:
                loaded = ca.external(fn.name(), str(target))
            except RuntimeError:  # damaged, or its kernels' libraries gone: run interpreted
                loaded = None
            if loaded is not None:
                _loaded[str(target)] = loaded
                while len(_loaded) > LOADED:
                    _loaded.popitem(last=False)
        if loaded is not None:
            _loaded.move_to_end(str(target))
    if loaded is not None:
        touch(target)
        return loaded
    request_function(fn, key, link=links(signatures))
    return None
