"""Compiling what a flexmech document's simulation runs on before a benchmark times it: its chain
kernels and its window of time steps, as `flexmech build DOC` does (service.kernels.needs), so
that the warm figures are the compiled ones a user has after one build. The compile time is
returned, to be printed beside the runs' figures (never hidden in them, never left out)."""

from __future__ import annotations

import time

from flexmech.models import Mechanism


def build_for(mech: Mechanism) -> float:
    """Wall seconds spent compiling the kernels and the window `mech`'s simulation needs (0 when
    the disk cache has them all)."""
    from flexmech.service.kernels.build import BuildLimits, Compiler
    from flexmech.service.kernels.needs import builds_of, window_builds

    compiler, limits = Compiler(), BuildLimits(600.0, 4 * 2**30)
    started = time.perf_counter()
    built = False
    for builds in (builds_of, window_builds):  # the window once the kernels it calls are there
        for b in builds(mech):
            for _, fn, target in b.functions:
                if not target.exists():
                    outcome = compiler.build(fn, target, limits, link=b.link)
                    assert outcome.ok, f"{b.name}: {outcome.to_json()}"
                    built = True
    return time.perf_counter() - started if built else 0.0
