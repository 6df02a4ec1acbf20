"""What compiling the kernels of every shipped example costs, on an empty cache: per example,
the generated C (all its kernels), the compiler's wall time and its peak memory (the largest
resident set of gcc and cc1), as the build queue runs it (-O2, one compiler at a time, niced).
A kernel shared with an earlier example is listed as shared and costs nothing again.

    python3 -m benchmarks.kernel_builds
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def main() -> None:
    from models import compile_mechanism, load_document
    from service.kernels.build import Compiler
    from service.kernels.needs import builds_of

    compiler = Compiler()
    print(f"  {'example':34s} {'kernels':>8s} {'C kB':>8s} {'largest C kB':>13s} {'compile s':>10s} "
          f"{'peak MiB':>9s}")
    worst = [0, 0.0, 0]
    for path in sorted(EXAMPLES.glob("*.json")):
        builds = builds_of(compile_mechanism(load_document(path)))
        if not builds:
            continue
        size = largest = peak = 0
        seconds, shared, count = 0.0, 0, 0
        for build in builds:
            for _, fn, target in build.functions:
                count += 1
                if target.exists():
                    shared += 1
                    continue
                outcome = compiler.build(fn, target)
                if not outcome.ok:
                    raise RuntimeError(f"{path.name}: {outcome.message}")
                size += outcome.c_bytes
                largest = max(largest, outcome.c_bytes)
                seconds += outcome.seconds
                peak = max(peak, outcome.peak_bytes)
        note = f" ({shared} shared)" if shared else ""
        print(f"  {path.name:34s} {count:8d} {size / 1e3:8.0f} {largest / 1e3:13.0f} {seconds:10.1f} "
              f"{peak / 2**20:9.0f}{note}")
        worst = [max(worst[0], size), max(worst[1], seconds), max(worst[2], peak)]
    print(f"  largest per example: {worst[0] / 1e6:.2f} MB of C, {worst[1]:.1f} s of compiling, "
          f"{worst[2] / 2**20:.0f} MiB peak")


if __name__ == "__main__":
    os.environ["FLEXMECH_CACHE_DIR"] = tempfile.mkdtemp(prefix="flexmech-builds-")  # empty: every build counted
    main()
