"""Work-precision of link dynamics against Exudyn, at equal accuracy (issue 50, Deliver 1; the rod
of Lan 2005 Ex. I.1 so far: the four-bar and Exudyn's ANCF element are still to come).

    pip install exudyn            # the peer (written against exudyn 1.13)
    python -m benchmarks.work_precision [--quick]

The same physics on both sides: the clamped steel rod of examples/rod_free_vibration.json
(bending, shear with kappa = 5/6, axial strain, rotary inertia), bent by its tip force in a static
solve and released from rest at t = 0; fixed steps. Each side is free to choose its
discretization: flexmech's cubic link elements (intervals) in generalized-alpha (rho_inf = 0.95)
and in sdirk4 (fourth order, five stages), and Exudyn's 2-node GeometricallyExactBeam2D elements
in generalized-alpha 0.95, each swept over element counts and steps.

Two measures, against a converged reference (flexmech sdirk4, 16 elements, 0.0625 ms: its time
error is below the second-order schemes' at any step swept), cross-checked against
generalized-alpha's and Exudyn's finest runs (the agreement is printed):
- first period: the time between the tip's first two downward zero crossings of y, relative;
- tip history: the largest tip deviation over [0, UNTIL] at common times (every 8 ms), over the
  tip's largest motion.
A configuration qualifies for a target only if it and every smaller step with the same elements
meet it (a lucky cancellation does not count); one at the smallest step swept only if a run at
half that step meets it too (run when it would be the cheapest). Cost: seconds of wall time per
simulated second, "warm" (the fastest of three repeat runs in the same process) and "cold" (the first run of the configuration in this
process: flexmech's graph and engine builds; Exudyn's model build and static solve). flexmech's
kernels and window are compiled first, as `flexmech build DOC` does once per structure and
scheme (benchmarks/flexmech_builds.py): that one-off compile is printed beside each
configuration ("compile s", 0 when the disk cache had it). Each side's cheapest qualifying
configuration per target is printed with the ratio.

Exudyn's settings: EigenSparse with reuseAnalyzedPattern above 16 elements, dense below; Newton
tolerances relative 1e-6, absolute 1e-8 N (its defaults, 1e-8 and 1e-10, stop its Newton at 64
elements and more: round-off; the run prints how far ten times tighter ones move the measures);
one thread.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

ROD_DOCUMENT = Path(__file__).resolve().parents[1] / "examples" / "rod_free_vibration.json"
UNTIL = 0.8  # s: holds the two downward zero crossings of the first mode (period 0.4715 s)
SAMPLE = 8e-3  # s: the common times the histories are compared at (the longest step swept divides it)
KAPPA = 5.0 / 6.0
TARGETS = (1e-3, 1e-4, 1e-5)
RHO_INF = 0.95
WARM_REPEATS = 3  # warm runs per configuration, the fastest counted: the machine is shared and noisy


# --- measures ---------------------------------------------------------------------------------------
def first_period(times: np.ndarray, y: np.ndarray) -> float:
    down = np.nonzero((y[:-1] > 0.0) & (y[1:] <= 0.0))[0]
    if len(down) < 2:
        return float("nan")
    crossings = times[down] + (times[down + 1] - times[down]) * y[down] / (y[down] - y[down + 1])
    return float(crossings[1] - crossings[0])


def sampled(times: np.ndarray, tip: np.ndarray) -> np.ndarray:
    """The tip at every SAMPLE (the runs' steps divide it: no interpolation)."""
    wanted = np.arange(0.0, UNTIL + 1e-12, SAMPLE)
    at = np.searchsorted(times, wanted - 1e-9)
    assert np.allclose(times[at], wanted, atol=1e-9), "a step that does not divide the sample time"
    return tip[at]


def errors(run: dict, reference: dict) -> tuple[float, float]:
    """(first period, tip history) relative errors of a run against a reference."""
    period = abs(run["period"] / reference["period"] - 1.0)
    motion = np.abs(reference["tip"] - reference["tip"][0]).max()
    history = float(np.abs(run["tip"] - reference["tip"]).max() / motion)
    return period, history


# --- flexmech -----------------------------------------------------------------------------------------
def flexmech_run(intervals: int, step: float, scheme: str = "generalized_alpha") -> dict:
    import flexmech

    document = json.loads(ROD_DOCUMENT.read_text())
    document["elements"]["rod"]["intervals"] = intervals
    document["sections"]["rod"]["shear_factor"] = KAPPA
    document["simulate"].update({"until": UNTIL, "step": step, "every": 1, "scheme": scheme, "rho_inf": RHO_INF})
    document["simulate"].pop("tolerance", None)
    from benchmarks.flexmech_builds import build_for

    compile_seconds = build_for(flexmech.load(document))  # as `flexmech build DOC` would, once
    timings = []
    for _ in range(1 + WARM_REPEATS):  # cold, then warm
        started = time.perf_counter()
        report = flexmech.simulate(flexmech.load(document)).report
        timings.append(time.perf_counter() - started)
    assert report["status"] == "finished", report["message"]
    times = np.asarray(report["times"])
    tip = np.c_[report["outputs"]["bodies.tip.x"], report["outputs"]["bodies.tip.y"]]
    return {
        "tip": sampled(times, tip),
        "period": first_period(times, tip[:, 1]),
        "cold": timings[0] / UNTIL,
        "warm": min(timings[1:]) / UNTIL,
        "compile": compile_seconds,
    }


# --- Exudyn ---------------------------------------------------------------------------------------------
def exudyn_run(elements: int, step: float, rel_tol: float = 1e-6, abs_tol: float = 1e-8) -> dict:
    import exudyn as exu

    from benchmarks.exudyn_peer import ROD, ROD_TIP_FORCE, _clamp, _Link, _settings

    def model(init=None, force=None):
        import exudyn.itemInterface as eii

        container = exu.SystemContainer()
        mbs = container.AddSystem()
        A, I = ROD["b"] * ROD["h"], ROD["b"] * ROD["h"] ** 3 / 12
        rod = _Link(mbs, (0.0, 0.0), (ROD["L"], 0.0), elements, ROD["E"], ROD["G"], ROD["rho"], A, I, KAPPA, init)
        _clamp(mbs, rod.nodes[0], (0, 1, 2))
        if force is not None:
            marker = mbs.AddMarker(eii.MarkerNodePosition(nodeNumber=rod.nodes[-1]))
            mbs.AddLoad(eii.LoadForceVector(markerNumber=marker, loadVector=[*force, 0.0]))
        return container, mbs, rod

    def settings():
        s = _settings(step, UNTIL, RHO_INF, rel_tol, abs_tol)
        if elements <= 16:
            s.linearSolver.solverType = exu.LinearSolverType.EXUdense
        else:
            s.linearSolver.reuseAnalyzedPattern = True
        s.parallel.numberOfThreads = 1
        return s

    timings = []
    for _ in range(1 + WARM_REPEATS):  # cold (model, static solve, run), then warm (the run again)
        started = time.perf_counter()
        if not timings:
            _cs, static, rod_s = model(force=ROD_TIP_FORCE)
            static.Assemble()
            s = settings()
            s.staticSolver.numberOfLoadSteps = 20
            if not static.SolveStatic(s, showHints=False, showCausingItems=False):
                raise RuntimeError("Exudyn static solver failed")
            shape = np.array([static.GetNodeOutput(n, exu.OutputVariableType.Coordinates) for n in rod_s.nodes])
        container, mbs, rod = model(init=shape)
        rod.add_sensors(mbs)
        mbs.Assemble()
        if timings:
            started = time.perf_counter()  # warm: the run alone
        if not mbs.SolveDynamic(settings(), showHints=False, showCausingItems=False):
            raise RuntimeError("Exudyn dynamic solver failed")
        timings.append(time.perf_counter() - started)
        times, q, _ = rod.histories(mbs)
    tip = rod.ref[None, -1, :2] + q[:, -1, :2]
    return {
        "tip": sampled(times, tip),
        "period": first_period(times, tip[:, 1]),
        "cold": timings[0] / UNTIL,
        "warm": min(timings[1:]) / UNTIL,
    }


def flexmech_reference(intervals: int, step: float) -> dict:
    """sdirk4 past the step limit of a call of flexmech.simulate (64000 stage solves here)."""
    import flexmech
    from flexmech.service.dynamics.run import run_simulation, simulation_spec

    document = json.loads(ROD_DOCUMENT.read_text())
    document["elements"]["rod"]["intervals"] = intervals
    document["sections"]["rod"]["shear_factor"] = KAPPA
    document["simulate"].update({"until": UNTIL, "step": step, "every": 1, "scheme": "sdirk4"})
    mech = flexmech.load(document)
    _, report = run_simulation(mech, simulation_spec(mech), max_steps=10**6)
    assert report["status"] == "finished", report["message"]
    times = np.asarray(report["times"])
    tip = np.c_[report["outputs"]["bodies.tip.x"], report["outputs"]["bodies.tip.y"]]
    return {"tip": sampled(times, tip), "period": first_period(times, tip[:, 1]), "cold": 0.0, "warm": 0.0}


def sdirk4_run(intervals: int, step: float) -> dict:
    return flexmech_run(intervals, step, "sdirk4")


# --- the sweep ----------------------------------------------------------------------------------------
def attempt(run, elements: int, step: float) -> dict | None:
    """A configuration's run, or None when its solver gives up (it qualifies for nothing)."""
    try:
        return run(elements, step)
    except Exception as exc:  # noqa: BLE001 (either side's solver failure, named in the table)
        print(f"{run.__name__} {elements} el @ {step * 1e3:g} ms failed: {str(exc).splitlines()[0][:160]}")
        return None


def cheapest(runs: dict, reference: dict, measure: int, target: float, cost: str, confirm=None) -> tuple | None:
    """(elements, step, seconds per second) of the cheapest configuration that meets `target` with
    every smaller step of its element count. A configuration at its element count's smallest
    swept step has no smaller one to vouch for it: confirm(elements, step) runs it at half the
    step, and it counts only if that run meets the target too."""
    qualified = []
    for (elements, step), run in runs.items():
        smaller = [r for (e, s), r in runs.items() if e == elements and s <= step]
        if all(r is not None and errors(r, reference)[measure] <= target for r in smaller):
            finest = step == min(s for e, s in runs if e == elements)
            qualified.append((run[cost], elements, step, finest))
    for seconds, elements, step, finest in sorted(qualified):
        if finest and confirm is not None:
            half = confirm(elements, step)
            if half is None or errors(half, reference)[measure] > target:
                continue
        return elements, step, seconds
    return None


def best_of(sides: dict, names: list[str], reference: dict, measure: int, target: float, cost: str):
    """(side, (elements, step, seconds per second)) of the cheapest qualifying configuration of
    the named sides; None if none reaches the target."""
    found = []
    for name in names:
        if name in sides:
            best = cheapest(
                sides[name], reference, measure, target, cost, lambda e, s, name=name: half_step(name, e, s)
            )
            if best is not None:
                found.append((name, best))
    return min(found, key=lambda nb: nb[1][2], default=None)


RUNS = {}  # side -> its run function (sweep fills it)
HALVES: dict = {}  # (side, elements, step) -> the run at half the step, made once


def half_step(side: str, elements: int, step: float) -> dict | None:
    key = (side, elements, step)
    if key not in HALVES:
        HALVES[key] = attempt(RUNS[side], elements, step / 2)
        if HALVES[key] is not None:
            print(f"(confirming {side} {elements} el @ {step * 1e3:g} ms by a run at {step * 5e2:g} ms)")
    return HALVES[key]


def sweep(quick: bool) -> dict[str, dict]:
    """Every side's runs, {side: {(elements, step): run or None}}."""
    steps = (4e-3, 2e-3, 1e-3) if quick else (8e-3, 4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4)
    ours_elements = (1, 2, 4) if quick else (1, 2, 4, 8, 16)
    peer_elements = (8, 16, 32) if quick else (8, 16, 32, 64, 128)
    RUNS.update({"flexmech g-alpha": flexmech_run, "flexmech sdirk4": sdirk4_run, "Exudyn GE": exudyn_run})
    sides = {
        "flexmech g-alpha": {(e, s): attempt(flexmech_run, e, s) for e in ours_elements for s in steps},
        "flexmech sdirk4": {(e, s): attempt(sdirk4_run, e, s) for e in ours_elements for s in steps},
        "Exudyn GE": {(e, s): attempt(exudyn_run, e, s) for e in peer_elements for s in steps},
    }
    try:
        from benchmarks.exudyn_ancf import ancf_rod_run
    except ImportError:  # the ANCF peer is optional
        return sides

    def ancf(elements: int, step: float) -> dict:
        return ancf_rod_run(elements, step, UNTIL, SAMPLE)

    RUNS["Exudyn ANCF"] = ancf
    sides["Exudyn ANCF"] = {(e, s): attempt(ancf, e, s) for e in peer_elements for s in steps}
    return sides


def references() -> dict:
    """flexmech's sdirk4 reference, cross-checked against the second-order finest runs."""
    reference = flexmech_reference(16, 6.25e-5)
    others = (
        ("flexmech generalized-alpha 16 el @ 0.125 ms", attempt(flexmech_run, 16, 1.25e-4)),
        ("Exudyn 256 GE @ 0.125 ms", attempt(exudyn_run, 256, 1.25e-4)),
    )
    for name, other in others:
        if other is not None:
            period_gap, history_gap = errors(other, reference)
            print(
                f"reference flexmech sdirk4 16 cubic elements @ 0.0625 ms (period {reference['period']:.7f} s) against "
                f"{name} (period {other['period']:.7f} s): {period_gap:.1e} (period), {history_gap:.1e} (tip history)"
            )
    return reference


def print_runs(sides: dict, reference: dict) -> None:
    print("\nconfiguration                        period err  history err  cold s/s  warm s/s  compile s")
    for name, runs in sides.items():
        for (e, s), run in runs.items():
            where = f"{name:17s} {e:4d} el @ {s * 1e3:5.3f} ms"
            if run is None:
                print(f"{where}  failed")
                continue
            p, h = errors(run, reference)
            print(
                f"{where}  {p:10.2e}  {h:11.2e}  {run['cold']:8.3f}  {run['warm']:8.3f}  {run.get('compile', 0.0):9.1f}"
            )


def print_targets(sides: dict, reference: dict) -> None:
    ours = [name for name in sides if name.startswith("flexmech")]
    peers = [name for name in sides if name.startswith("Exudyn")]
    print(
        "\ntarget  measure       flexmech (cheapest, warm)             Exudyn (cheapest, warm)               ratio | cold"
    )

    def text(best) -> str:
        return (
            "not reached" if best is None else f"{best[0]} {best[1][0]} el @ {best[1][1] * 1e3:g} ms, {best[1][2]:.3f}"
        )

    for target in TARGETS:
        for measure, label in ((0, "first period"), (1, "tip history")):
            a, b = (best_of(sides, names, reference, measure, target, "warm") for names in (ours, peers))
            ac, bc = (best_of(sides, names, reference, measure, target, "cold") for names in (ours, peers))
            ratio = f"{b[1][2] / a[1][2]:.2f}x" if a and b else "-"
            cold = f"{bc[1][2] / ac[1][2]:.2f}x" if ac and bc else "-"
            print(f"{target:6.0e}  {label:12s}  {text(a):36s}  {text(b):36s}  {ratio:>6s} | {cold}")


def plot(sides: dict, reference: dict, path: str) -> None:
    """Error against warm seconds per simulated second, one panel per measure, every run."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for measure, (ax, label) in enumerate(zip(axes, ("first period", "tip history over 0.8 s"))):
        for name, runs in sides.items():
            done = sorted((run["warm"], errors(run, reference)[measure]) for run in runs.values() if run is not None)
            (dots,) = ax.loglog(*zip(*done), "o", alpha=0.5, label=name)
            front = [(c, e) for k, (c, e) in enumerate(done) if e < min((q for _, q in done[:k]), default=np.inf)]
            ax.loglog(*zip(*front), "-", drawstyle="steps-post", color=dots.get_color())  # the cheapest per error
        ax.set(xlabel="wall s per simulated s (warm)", ylabel="relative error", title=f"rod: {label}")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"\nplot: {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer configurations (a smoke run)")
    parser.add_argument("--plot", metavar="PNG", help="write the work-precision plot there")
    args = parser.parse_args()
    print(f"model: clamped steel rod {ROD_DOCUMENT.name}, kappa {KAPPA:.4f}, released at t = 0, until {UNTIL} s")
    reference = references()
    loose, tight = exudyn_run(32, 5e-4), exudyn_run(32, 5e-4, 1e-7, 1e-9)
    moved = errors(loose, tight)
    print(
        f"Exudyn's tolerances: ten times tighter ones move 32 el @ 0.5 ms by {moved[0]:.1e} (period) and "
        f"{moved[1]:.1e} (tip history)"
    )
    sides = sweep(args.quick)
    print_runs(sides, reference)
    print_targets(sides, reference)
    if args.plot:
        plot(sides, reference, args.plot)


if __name__ == "__main__":
    main()
