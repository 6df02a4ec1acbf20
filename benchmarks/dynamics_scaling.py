"""How the cost of a time step grows with the element count: the rod of Example I.1
(examples/rod_free_vibration.json: bending, shear and axial strain; h = 1 ms, generalized-alpha
0.95) with 8 to 64 cubic elements in flexmech (warm: kernels compiled, engine built), beside
Exudyn with as many linear GeometricallyExactBeam2D elements, both for 0.5 s from the same
held shape. Printed per element count: wall seconds per step, flexmech's Newton iterations per
step, and the exponent of a power law fitted to the seconds per step between 16 and 64
elements (1: linear).

The peer: pip install "flexmech[bench]" (exudyn). Run from the repository root:

    python3 -m benchmarks.dynamics_scaling
"""

from __future__ import annotations

import os
import tempfile

import numpy as np

from benchmarks.dynamics import compile_kernels, document, flexmech_run

COUNTS = (8, 16, 32, 64)  # 64: the most elements a link takes (models.elements.link: intervals)
UNTIL = 0.5


def exponent(counts, seconds) -> float:
    """The slope of log(seconds) against log(count), by least squares, from 16 elements up."""
    pairs = [(np.log(n), np.log(s)) for n, s in zip(counts, seconds) if n >= 16]
    x, y = np.array(pairs).T
    return float(np.polyfit(x, y, 1)[0])


def main() -> None:
    from benchmarks.exudyn_peer import rod_free_vibration

    ours, theirs, iterations = [], [], []
    for n in COUNTS:
        mech = document("rod_free_vibration.json", lambda d, n=n: d["elements"]["rod"].update(intervals=n))
        compile_kernels(mech)
        report, _ = flexmech_run(mech, until=UNTIL, every=50)
        ours.append(report["seconds"] / report["steps"])
        iterations.append(report["iterations"] / report["steps"])
        peer = rod_free_vibration(elements=n, step=1e-3, until=UNTIL, rho_inf=0.95)
        theirs.append(peer["wall_seconds"] / round(UNTIL / 1e-3))
    print(f"Rod of Example I.1, {UNTIL:g} s in steps of 1 ms; bending, shear and axial strain on both sides")
    print(f"  {'elements':>8s} {'flexmech ms/step':>17s} {'iterations/step':>16s} {'Exudyn ms/step':>15s} "
          f"{'ratio':>7s}")
    for n, a, k, b in zip(COUNTS, ours, iterations, theirs):
        print(f"  {n:8d} {a * 1e3:17.3f} {k:16.2f} {b * 1e3:15.3f} {a / b:7.2f}")
    print(f"  fitted exponent (16 to 64 elements): flexmech {exponent(COUNTS, ours):.2f}, "
          f"Exudyn {exponent(COUNTS, theirs):.2f}")


if __name__ == "__main__":
    os.environ.setdefault("FLEXMECH_CACHE_DIR", tempfile.mkdtemp(prefix="flexmech-bench-"))
    main()
