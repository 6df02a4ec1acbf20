"""What compiling the kernels of every shipped example costs, on an empty cache: per example,
the generated C (all its kernels, and the window of time steps that calls them:
service.kernels.windows), the compiler's wall time and its peak memory (the largest resident
set of gcc and cc1), as the build queue runs it (one compiler at a time). A kernel shared with
an earlier example is listed as shared and costs nothing again; the window is the structure's
own.

    python3 -m benchmarks.kernel_builds
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


class Totals:
    """One example's builds: C bytes, the largest library's, the window's, compile seconds,
    peak memory, how many and how many were shared."""

    def __init__(self):
        self.size = self.largest = self.window = self.peak = self.count = self.shared = 0
        self.seconds = 0.0

    def compile(self, build, compiler) -> None:
        for part, fn, target in build.functions:
            self.count += 1
            if target.exists():
                self.shared += 1
                continue
            outcome = compiler.build(fn, target, link=build.link)
            if not outcome.ok:
                raise RuntimeError(f"{build.name}: {outcome.message}")
            self.size += outcome.c_bytes
            self.largest = max(self.largest, outcome.c_bytes)
            self.window = outcome.c_bytes if part == "window" else self.window
            self.seconds += outcome.seconds
            self.peak = max(self.peak, outcome.peak_bytes)


def main() -> None:
    from flexmech.models import compile_mechanism, load_document
    from flexmech.service.kernels.build import Compiler
    from flexmech.service.kernels.needs import builds_of, window_builds

    compiler = Compiler()
    print(
        f"  {'example':34s} {'builds':>8s} {'C kB':>8s} {'largest C kB':>13s} {'window kB':>10s} "
        f"{'compile s':>10s} {'peak MiB':>9s}"
    )
    worst = [0, 0.0, 0]
    for path in sorted(EXAMPLES.glob("*.json")):
        mech = compile_mechanism(load_document(path))
        if not builds_of(mech):
            continue
        totals = Totals()
        for build in builds_of(mech):
            totals.compile(build, compiler)
        for build in window_builds(mech):  # once the kernels it calls are there
            totals.compile(build, compiler)
        note = f" ({totals.shared} shared)" if totals.shared else ""
        window = f"{totals.window / 1e3:.0f}" if totals.window else "-"
        print(
            f"  {path.name:34s} {totals.count:8d} {totals.size / 1e3:8.0f} {totals.largest / 1e3:13.0f} "
            f"{window:>10s} {totals.seconds:10.1f} {totals.peak / 2**20:9.0f}{note}"
        )
        worst = [max(worst[0], totals.size), max(worst[1], totals.seconds), max(worst[2], totals.peak)]
    print(
        f"  largest per example: {worst[0] / 1e6:.2f} MB of C, {worst[1]:.1f} s of compiling, "
        f"{worst[2] / 2**20:.0f} MiB peak"
    )


if __name__ == "__main__":
    os.environ["FLEXMECH_CACHE_DIR"] = tempfile.mkdtemp(prefix="flexmech-builds-")  # empty: every build counted
    main()
