"""Work-precision of link dynamics against Exudyn on the compliant four-bar (Lan 2005 Ex. II.2,
examples/four_bar_dynamics.json), at equal accuracy (issue 50, Deliver 1; the rod is
benchmarks/work_precision.py, whose rules this follows).

    pip install exudyn            # the peer (written against exudyn 1.13)
    python -m benchmarks.work_precision_four_bar [--quick]

The same physics on both sides (benchmarks/exudyn_peer.four_bar: the document's links, shear factor
0.9, G = E / 2.6, the drive moment's ramp table, no gravity), from rest to 0.5 s. Each side is free
to choose its discretization: flexmech's cubic link elements (crank/coupler/follower intervals) in
generalized-alpha 0.95 and sdirk4, fixed steps and adaptive; Exudyn's GeometricallyExactBeam2D
elements in generalized-alpha 0.95, fixed steps (the fastest settings of exudyn_peer.four_bar).

Two measures at 0.5 s, relative, against a converged reference (flexmech generalized-alpha,
4/8/8 elements, 0.0625 and 0.03125 ms extrapolated), cross-checked against sdirk4, twice the
elements and Exudyn (printed):
- crank angle: the crank's rotation at its pivot;
- input work: the drive moment's work since t = 0.
A fixed-step configuration qualifies for a target only if every smaller step with the same
elements also meets it; an adaptive one, if every tighter tolerance does; one at the finest
setting swept, if a run at half its step (a tenth of its tolerance) does. Cost: wall seconds per
simulated second, warm (the fastest of three repeats in the same process) and cold (the first run of the
configuration in the process, builds counted); flexmech's one-off compile of its kernels and
window (`flexmech build DOC`, benchmarks/flexmech_builds.py) is printed beside, 0 when cached.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

FOUR_BAR_DOCUMENT = Path(__file__).resolve().parents[1] / "examples" / "four_bar_dynamics.json"
UNTIL = 0.5  # s
WARM_REPEATS = 3  # warm runs per configuration, the fastest counted: the machine is shared and noisy
TARGETS = (1e-3, 1e-4, 1e-5)
LINKS = ("crank", "coupler", "follower")


def _document(elements: tuple[int, int, int], step: float, scheme: str, tolerance: float | None) -> dict:
    document = json.loads(FOUR_BAR_DOCUMENT.read_text())
    for name, count in zip(LINKS, elements):
        document["elements"][name]["intervals"] = count
    simulate = document["simulate"]
    simulate.update({"until": UNTIL, "step": step, "every": 10**6, "scheme": scheme, "rho_inf": 0.95})
    simulate.update({"adaptive": tolerance is not None, "tolerance": tolerance or 1e-6})
    return document


def _measures(report: dict) -> dict:
    assert report["status"] == "finished", report["message"]
    angle = report["outputs"]["bodies.crank_pivot.angle"][-1]
    return {
        "angle": math.radians(angle) if report["units"]["angle"] == "deg" else angle,
        "work": report["energies"]["input_work"][-1],
        "steps": report["steps"],
    }


def flexmech_run(elements: tuple[int, int, int], step: float, scheme: str, tolerance: float | None = None) -> dict:
    import flexmech

    document = _document(elements, step, scheme, tolerance)
    from benchmarks.flexmech_builds import build_for

    compile_seconds = build_for(flexmech.load(document))  # as `flexmech build DOC` would, once
    timings = []
    for _ in range(1 + WARM_REPEATS):  # cold, then warm
        started = time.perf_counter()
        report = flexmech.simulate(flexmech.load(document)).report
        timings.append(time.perf_counter() - started)
    warm = min(timings[1:]) / UNTIL
    return {**_measures(report), "cold": timings[0] / UNTIL, "warm": warm, "compile": compile_seconds}


def flexmech_reference(elements: tuple[int, int, int], step: float, scheme: str) -> dict:
    """A run past a call's step limit."""
    import flexmech
    from flexmech.service.dynamics.run import run_simulation, simulation_spec

    mech = flexmech.load(_document(elements, step, scheme, None))
    _, report = run_simulation(mech, simulation_spec(mech), max_steps=10**6)
    return {**_measures(report), "cold": 0.0, "warm": 0.0}


def references() -> dict:
    """Generalized-alpha at 4/8/8 elements, 0.0625 and 0.03125 ms, extrapolated (its error falls
    as h^2: sdirk4's falls as h^1.3 here, docs/dynamics.md), cross-checked against sdirk4 and
    Exudyn; the extrapolation's change is printed as the reference's own error."""
    coarse, fine = (flexmech_reference((4, 8, 8), h, "generalized_alpha") for h in (6.25e-5, 3.125e-5))
    reference = {k: (4 * fine[k] - coarse[k]) / 3 for k in ("angle", "work")}
    print(
        f"reference: flexmech generalized-alpha 4/8/8 at 0.0625 and 0.03125 ms, extrapolated: crank "
        f"{reference['angle']:.9f} rad, work {reference['work']:.9f} J (the extrapolation moved the 0.03125 ms "
        f"run by {error(fine, reference, 'angle'):.1e} and {error(fine, reference, 'work'):.1e})"
    )
    for name, other in (
        ("flexmech sdirk4 4/8/8 @ 0.0625 ms", flexmech_reference((4, 8, 8), 6.25e-5, "sdirk4")),
        (
            "flexmech generalized-alpha 8/16/16 @ 0.0625 ms",
            flexmech_reference((8, 16, 16), 6.25e-5, "generalized_alpha"),
        ),
        ("Exudyn GE 32/64/64 @ 0.25 ms", attempt(exudyn_run, (32, 64, 64), 2.5e-4)),
    ):
        if other is not None:
            agreement = f"crank {error(other, reference, 'angle'):.1e}, work {error(other, reference, 'work'):.1e}"
            print(f"  against {name}: {agreement}")
    return reference


def exudyn_run(elements: tuple[int, int, int], step: float) -> dict:
    from benchmarks.exudyn_peer import four_bar

    timings = []
    for _ in range(1 + WARM_REPEATS):  # cold, then warm
        started = time.perf_counter()
        run = four_bar(elements, step, UNTIL)
        timings.append(time.perf_counter() - started)
    return {
        "angle": float(run["crank_angle"][-1]),
        "work": float(run["input_work"][-1]),
        "steps": None,
        **{
            "cold": timings[0] / UNTIL,
            "warm": min(timings[1:]) / UNTIL,
        },
    }


def error(run: dict, reference: dict, measure: str) -> float:
    return abs(run[measure] / reference[measure] - 1.0)


def attempt(run, *args) -> dict | None:
    """A configuration's run, or None when its solver gives up (it qualifies for nothing)."""
    try:
        return run(*args)
    except Exception as exc:  # noqa: BLE001 (either side's solver failure, named in the table)
        print(f"{getattr(run, '__name__', run)} {args} failed: {str(exc).splitlines()[0][:120]}")
        return None


def cheapest(runs: dict, reference: dict, measure: str, target: float, cost: str, confirm=None) -> tuple | None:
    """(configuration, seconds per second) of the cheapest one that meets `target` with every
    finer setting of its element counts (smaller step or tighter tolerance). One at its
    element counts' finest setting swept counts only if confirm(elements, setting), a run at
    half the step or a tenth of the tolerance, meets the target too."""
    qualified = []
    for (elements, setting), run in runs.items():
        finer = [r for (e, s), r in runs.items() if e == elements and s <= setting]
        if all(r is not None and error(r, reference, measure) <= target for r in finer):
            finest = setting == min(s for e, s in runs if e == elements)
            qualified.append((run[cost], elements, setting, finest))
    for seconds, elements, setting, finest in sorted(qualified):
        if finest and confirm is not None:
            finer_run = confirm(elements, setting)
            if finer_run is None or error(finer_run, reference, measure) > target:
                continue
        return (elements, setting), seconds
    return None


CONFIRMED: dict = {}  # (side, elements, setting) -> the run one setting finer, made once


def confirm_of(side: str):
    scheme = side.split()[0]

    def confirm(elements, setting):
        key = (side, elements, setting)
        if key not in CONFIRMED:
            if side.startswith("Exudyn"):
                CONFIRMED[key] = attempt(exudyn_run, elements, setting / 2)
            elif side.endswith("adaptive"):
                CONFIRMED[key] = attempt(flexmech_run, elements, 1e-3, scheme, setting / 10)
            else:
                CONFIRMED[key] = attempt(flexmech_run, elements, setting / 2, scheme)
            print(f"(confirming {side} {elements} {setting:g} by a finer run)")
        return CONFIRMED[key]

    return confirm


def sweep(quick: bool) -> dict[str, dict]:
    steps = (4e-3, 2e-3, 1e-3) if quick else (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4)
    tolerances = (1e-4, 1e-5, 1e-6) if quick else (1e-4, 1e-5, 1e-6, 1e-7)
    ours = ((1, 2, 2), (2, 4, 4)) if quick else ((1, 2, 2), (2, 4, 4), (4, 8, 8))
    peer = ((8, 16, 16), (16, 32, 32)) if quick else ((8, 16, 16), (16, 32, 32), (32, 64, 64))
    runs = {}
    for scheme in ("generalized_alpha", "sdirk4"):
        runs[f"{scheme} fixed"] = {(e, s): attempt(flexmech_run, e, s, scheme) for e in ours for s in steps}
        runs[f"{scheme} adaptive"] = {
            (e, t): attempt(flexmech_run, e, 1e-3, scheme, t) for e in ours for t in tolerances
        }
    runs["Exudyn GE fixed"] = {(e, s): attempt(exudyn_run, e, s) for e in peer for s in steps}
    return runs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer configurations (a smoke run)")
    quick = parser.parse_args().quick
    print(f"model: {FOUR_BAR_DOCUMENT.name} (Lan 2005 Ex. II.2), from rest to {UNTIL} s")
    reference = references()
    runs = sweep(quick)
    print("\nside                        configuration        crank err   work err   cold s/s  warm s/s  compile s")
    for side, table in runs.items():
        for (elements, setting), run in table.items():
            label = f"{'/'.join(map(str, elements))} {'tol' if 'adaptive' in side else '@'} {setting:g}"
            if run is None:
                print(f"{side:27s} {label:20s} failed")
                continue
            print(
                f"{side:27s} {label:20s} {error(run, reference, 'angle'):9.2e}  {error(run, reference, 'work'):9.2e}"
                f"  {run['cold']:8.3f}  {run['warm']:8.3f}  {run.get('compile', 0.0):9.1f}"
            )
    print(
        "\ntarget  measure  flexmech (cheapest, warm)                      Exudyn GE (cheapest, warm)       ratio | cold"
    )
    for target in TARGETS:
        for measure in ("angle", "work"):
            row = []
            for cost in ("warm", "cold"):
                ours = [
                    (side, cheapest(t, reference, measure, target, cost, confirm_of(side)))
                    for side, t in runs.items()
                    if "Exudyn" not in side
                ]
                ours = [(side, best) for side, best in ours if best is not None]
                a = min(ours, key=lambda sb: sb[1][1], default=None)
                b = cheapest(runs["Exudyn GE fixed"], reference, measure, target, cost, confirm_of("Exudyn GE fixed"))
                row.append((a, b))
            (a, b), (ac, bc) = row
            text_a = "not reached" if a is None else f"{a[0]} {a[1][0]}, {a[1][1]:.3f} s/s"
            text_b = "not reached" if b is None else f"{b[0]}, {b[1]:.3f} s/s"
            ratio = f"{b[1] / a[1][1]:.2f}x" if a and b else "-"
            cold = f"{bc[1] / ac[1][1]:.2f}x" if ac and bc else "-"
            print(f"{target:6.0e}  {measure:7s}  {text_a:45s}  {text_b:31s}  {ratio:>6s} | {cold}")


if __name__ == "__main__":
    main()
