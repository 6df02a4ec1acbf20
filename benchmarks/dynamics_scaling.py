"""How the cost of a time step grows with the element count: the rod of Example I.1
(examples/rod_free_vibration.json: bending, shear and axial strain; h = 1 ms, generalized-alpha
0.95) with 8 to 128 cubic elements in flexmech (warm: kernels compiled, engine built), beside
Exudyn with as many linear GeometricallyExactBeam2D elements, both for 0.5 s from the same
held shape. Printed per element count: wall seconds per step, flexmech's Newton iterations per
step, the held tip's height at the start (the same shape on both sides), and the exponent of a
power law fitted to the seconds per step between 16 and 128 elements (1: linear).

flexmech's side is the stepping alone (service.dynamics.integrate from the static start on the
kernels), as the report's `seconds` counts it. Printed apart, per element count: the report of
the run (its outputs' graphs built for the new structure, then evaluated on the kept states),
and the first statics solve of the same structure in the process (service.solvers.equilibrium: it
builds the dense residual form and its tangent), both on an empty graph cache.

The peer: pip install "flexmech[bench]" (exudyn). Run from the repository root:

    python3 -m benchmarks.dynamics_scaling
"""

from __future__ import annotations

import os
import tempfile
import time

import numpy as np

from benchmarks.dynamics import compile_kernels, document

COUNTS = (8, 16, 32, 64, 128)  # 128: the most elements a link takes (models.elements.link: intervals)
UNTIL = 0.5


def stepping(mech, until: float) -> tuple[float, float, float, float]:
    """(wall seconds per step, Newton iterations per step, the tip's start height in m, seconds
    of the report) of the document's run to `until`, after a first short run that builds the
    engine and its window."""
    from flexmech.service.dynamics.histories import read_histories
    from flexmech.service.dynamics.integrate import integrate
    from flexmech.service.dynamics.run import report, scheme_of, simulated, simulation_spec, start_shape

    spec = simulation_spec(mech, {"until": until})
    histories = read_histories(mech, spec.histories, spec.until)
    x0, _ = start_shape(mech, spec, histories)
    p, scheme = mech.p(), scheme_of(spec)
    integrate(mech.structure, p, x0, 0 * x0, 40 * spec.step, spec.step, scheme, histories=histories, every=50)
    history = integrate(mech.structure, p, x0, 0 * x0, until, spec.step, scheme, histories=histories, every=50)
    if history.status != "finished":
        raise SystemExit(f"{history.status}: {history.message}")
    tip = mech.structure.bodies.index("tip")
    layout_of_x = [k for k, (b, c) in enumerate(mech.structure.free) if b == tip and c == 1]
    height = float(x0[layout_of_x[0]]) / mech.nd_per_doc("length") if layout_of_x else float("nan")
    started = time.perf_counter()
    report(simulated(mech), spec, history, histories, "")
    reported = time.perf_counter() - started
    return history.seconds / history.steps, history.iterations / history.steps, height, reported


def first_statics_solve(mech) -> float:
    """Seconds of the first statics solve of the structure (its residual form built anew)."""
    from flexmech.models.graph.assembly import _symbolic
    from flexmech.service.solvers.equilibrium import solve_equilibrium

    _symbolic.cache_clear()  # the report's expressions are not reused: a structure new to the process
    started = time.perf_counter()
    result = solve_equilibrium(mech)
    if result.status != "converged":
        raise SystemExit(f"statics: {result.status}")
    return time.perf_counter() - started


def exponent(counts, seconds) -> float:
    """The slope of log(seconds) against log(count), by least squares, from 16 elements up
    (over the counts that ran)."""
    pairs = [(np.log(n), np.log(s)) for n, s in zip(counts, seconds) if n >= 16 and np.isfinite(s)]
    x, y = np.array(pairs).T
    return float(np.polyfit(x, y, 1)[0])


def main() -> None:
    from benchmarks.exudyn_peer import rod_free_vibration

    ours, theirs, iterations, heights, reports, statics = [], [], [], [], [], []
    for n in COUNTS:
        mech = document("rod_free_vibration.json", lambda d, n=n: d["elements"]["rod"].update(intervals=n))
        compile_kernels(mech)
        seconds, per_step, height, reported = stepping(mech, UNTIL)
        reports.append(reported)
        statics.append(first_statics_solve(mech))
        ours.append(seconds)
        iterations.append(per_step)
        heights.append(height)
        try:
            peer = rod_free_vibration(elements=n, step=1e-3, until=UNTIL, rho_inf=0.95)
            theirs.append((peer["wall_seconds"] / round(UNTIL / 1e-3), float(peer["tip_y"][0])))
        except RuntimeError as exc:  # exudyn.SolverError is one: at 128 elements (1, 0.5 and 0.25 ms alike)
            print(f"Exudyn, {n} elements: {exc}")
            theirs.append((float("nan"), float("nan")))
    print(f"Rod of Example I.1, {UNTIL:g} s in steps of 1 ms; bending, shear and axial strain on both sides")
    print(
        f"  {'elements':>8s} {'flexmech ms/step':>17s} {'iterations/step':>16s} {'tip y at start, m':>18s} "
        f"{'Exudyn ms/step':>15s} {'ratio':>7s}"
    )
    for n, a, k, y, (b, y_peer) in zip(COUNTS, ours, iterations, heights, theirs):
        print(
            f"  {n:8d} {a * 1e3:17.3f} {k:16.2f} {y:18.10f} {b * 1e3:15.3f} {a / b:7.2f}   (Exudyn's tip y at "
            f"start {y_peer:.10f} m)"
        )
    ran = [n for n, (b, _) in zip(COUNTS, theirs) if np.isfinite(b)]
    print(
        f"  fitted exponent (16 to 128 elements): flexmech {exponent(COUNTS, ours):.2f}; "
        f"Exudyn (16 to {max(ran)}) {exponent(COUNTS, [b for b, _ in theirs]):.2f}"
    )
    print("  the same structures, new to the process, on an empty graph cache: seconds of")
    print(f"  {'elements':>8s} {'the run report':>15s} {'first statics solve':>20s}")
    for n, r, f in zip(COUNTS, reports, statics):
        print(f"  {n:8d} {r:15.2f} {f:20.2f}")


if __name__ == "__main__":
    os.environ.setdefault("FLEXMECH_CACHE_DIR", tempfile.mkdtemp(prefix="flexmech-bench-"))
    main()
