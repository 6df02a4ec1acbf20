"""Link dynamics against Exudyn, the same physics side by side in one run (Lan 2005 Ch. 4).

Both sides model bending, shear and axial strain (Simo-Reissner beams) and print their model:
element type and count, step, scheme.

  Example I.1: examples/rod_free_vibration.json as shipped (8 cubic elements, h = 1 ms,
      generalized-alpha rho_inf 0.95), released from its held shape, 5 s (ten periods).
      Accuracy: the period (mean over the run) against a converged one (flexmech, 16 cubic
      elements, h = 0.25 ms) and the energy drift max |E/E0 - 1|; the same motion shows in the
      period itself.
  Example II.2: examples/four_bar_dynamics.json as shipped (2/4/4 cubic elements, adaptive
      steps to a local error of 1e-5), 1 s (the coupler buckles at about 1 s; after that the
      motion is chaotic and no two models agree). Accuracy: the energy balance
      max |T + U - W| / max W. Same motion: the input work W at 1 s and the crank's largest
      rotation, 186.92 J and 6.5944 rad.

Figures: wall seconds per simulated second of the integration alone on both sides (flexmech:
the windows of steps and the start's accelerations; Exudyn: SolveDynamic), warm: flexmech's
kernels compiled (their compile time printed apart, once per kernel family, shared by every
structure), its engine built by a first short run (printed too). "interpreted": the same run
before any kernel is compiled (what the first run on an empty cache does). "cold": a whole
`flexmech simulate examples/rod_free_vibration.json --until 1` process on an empty cache.
Peer rows sweep Exudyn's element count or step to show where it reaches flexmech's accuracy.

The peer: pip install "flexmech[bench]" (exudyn). Run from the repository root:

    python3 -m benchmarks.dynamics
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ROD_UNTIL, BAR_UNTIL = 5.0, 1.0


def document(example: str, edit=None):
    from flexmech.models import compile_mechanism, load_document

    data = json.loads((EXAMPLES / example).read_text())
    if edit is not None:
        edit(data)
    return compile_mechanism(load_document(data))


def compile_kernels(mech) -> float:
    """Compile the kernels the mechanism runs on, then the window that calls them (if not yet):
    seconds of compiling."""
    from flexmech.service.kernels.build import Compiler
    from flexmech.service.kernels.needs import builds_of, window_builds

    seconds = 0.0
    compiler = Compiler()
    for builds in (lambda: builds_of(mech), lambda: window_builds(mech)):
        for build in builds():
            for _, fn, target in build.functions:
                if not target.exists():
                    outcome = compiler.build(fn, target, link=build.link)
                    if not outcome.ok:
                        raise RuntimeError(outcome.message)
                    seconds += outcome.seconds
    return seconds


def flexmech_run(mech, **fields) -> tuple[dict, float]:
    """(report, seconds of the engine's build in a first short run); the report's `seconds`
    is the integration of the timed run alone (no static start, no report)."""
    from flexmech.service.dynamics.run import run_simulation, simulation_spec

    started = time.perf_counter()
    run_simulation(mech, simulation_spec(mech, {**fields, "until": 20 * fields.get("step", 1e-3)}))
    built = time.perf_counter() - started
    _, report = run_simulation(mech, simulation_spec(mech, fields))
    return report, built


def period_and_drift(times, tip_y, kinetic, potential) -> tuple[float, float]:
    t, y = np.asarray(times), np.asarray(tip_y)
    crossings = np.array(
        [t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i]) for i in range(len(y) - 1) if y[i] > 0 >= y[i + 1]]
    )
    energy = np.asarray(kinetic) + np.asarray(potential)
    return float(np.mean(np.diff(crossings))), float(np.abs(energy / energy[0] - 1).max())


def _flexmech_rod_row(name: str, report: dict) -> tuple:
    period, drift = period_and_drift(
        report["times"],
        report["outputs"]["bodies.tip.y"],
        report["energies"]["kinetic"],
        report["energies"]["potential"],
    )
    return name, period, drift, report["seconds"] / ROD_UNTIL


def cold_process_seconds() -> float:
    """A whole `flexmech simulate ... --until 1` on an empty cache (a fresh process)."""
    with tempfile.TemporaryDirectory() as cache:
        started = time.perf_counter()
        subprocess.run(
            [
                sys.executable,
                "-m",
                "flexmech.api.cli",
                "simulate",
                str(EXAMPLES / "rod_free_vibration.json"),
                "--until",
                "1",
            ],
            check=True,
            capture_output=True,
            env={**os.environ, "FLEXMECH_CACHE_DIR": cache},
        )
        return time.perf_counter() - started


def rod(interpreted: dict) -> None:
    from benchmarks.exudyn_peer import rod_free_vibration

    def intervals(n):
        return lambda d: d["elements"]["rod"].update(intervals=n)

    shipped = document("rod_free_vibration.json")
    fine = document("rod_free_vibration.json", intervals(16))
    compiled = compile_kernels(shipped)
    from flexmech.service.dynamics.engine import _engines

    _engines.clear()  # the engines built on interpreted kernels go: the next run loads the compiled ones
    warm, built = flexmech_run(shipped, until=ROD_UNTIL, every=1)
    reference_report, _ = flexmech_run(fine, until=ROD_UNTIL, every=4, step=0.00025)
    reference, _ = period_and_drift(
        reference_report["times"],
        reference_report["outputs"]["bodies.tip.y"],
        reference_report["energies"]["kinetic"],
        reference_report["energies"]["potential"],
    )
    rows = [
        _flexmech_rod_row("flexmech 8 cubic, warm", warm),
        _flexmech_rod_row("flexmech 8 cubic, interpreted", interpreted),
    ]
    for elements in (8, 10, 12, 16):
        peer = rod_free_vibration(elements=elements, step=1e-3, until=ROD_UNTIL, rho_inf=0.95)
        rows.append(
            (f"Exudyn {elements} linear", peer["period"], peer["energy_drift"], peer["wall_seconds"] / ROD_UNTIL)
        )
    cold = cold_process_seconds()
    print(
        f"Example I.1, {ROD_UNTIL:g} s; bending, shear and axial strain on both sides; h = 1 ms, "
        f"generalized-alpha rho_inf 0.95"
    )
    print(f"  reference period {reference:.6f} s (flexmech 16 cubic elements, h = 0.25 ms)")
    print(f"  {'run':32s} {'period s':>10s} {'error':>9s} {'drift':>9s} {'wall s per s':>13s} {'vs flexmech':>12s}")
    for name, period, drift, per_second in rows:
        print(
            f"  {name:32s} {period:10.6f} {abs(period / reference - 1):9.1e} {drift:9.1e} {per_second:13.3f} "
            f"{per_second / rows[0][3]:11.2f}x"
        )
    print(
        f"  flexmech: {warm['steps']} steps, {warm['iterations'] / max(warm['steps'], 1):.2f} Newton "
        f"iterations per step; kernels and window compiled once in {compiled:.1f} s (the kernels shared by every "
        f"structure of this element family, the window this structure's), engine built in {built:.2f} s"
    )
    print(f"  cold: the whole `flexmech simulate rod_free_vibration.json --until 1` on an empty cache: {cold:.1f} s")
    accurate = [row for row in rows[2:] if abs(row[1] / reference - 1) <= 1e-3]
    if accurate:
        print(
            f"  the first Exudyn model with the period to 1e-3 ({accurate[0][0]}) takes "
            f"{accurate[0][3] / rows[0][3]:.2f}x flexmech's warm time"
        )


def four_bar(interpreted: dict) -> None:
    from benchmarks.exudyn_peer import four_bar as peer_four_bar

    shipped = document("four_bar_dynamics.json")
    compiled = compile_kernels(shipped)
    from flexmech.service.dynamics.engine import _engines

    _engines.clear()
    warm, built = flexmech_run(shipped, until=BAR_UNTIL, every=1)
    rows = []
    for name, report in (
        ("flexmech 2/4/4 cubic, adaptive, warm", warm),
        ("flexmech 2/4/4 cubic, adaptive, interp.", interpreted),
    ):
        angle = np.radians(np.abs(report["outputs"]["elements.crank.angle_start"])).max()
        rows.append(
            (
                name,
                report["energy_balance_error"],
                report["energies"]["input_work"][-1],
                angle,
                report["steps"],
                report["seconds"] / BAR_UNTIL,
            )
        )
    for step in (1e-3, 2.5e-4, 1e-4):
        peer = peer_four_bar(elements=(8, 16, 16), step=step, until=BAR_UNTIL, rho_inf=0.95)
        rows.append(
            (
                f"Exudyn 8/16/16 linear, h = {step * 1e3:g} ms",
                peer["balance_error"],
                peer["input_work"][-1],
                float(np.abs(peer["crank_angle"]).max()),
                len(peer["times"]) - 1,
                peer["wall_seconds"] / BAR_UNTIL,
            )
        )
    print(f"\nExample II.2, {BAR_UNTIL:g} s; bending, shear and axial strain on both sides")
    print(
        f"  {'run':40s} {'balance':>9s} {'work J':>9s} {'crank rad':>10s} {'steps':>6s} {'wall s per s':>13s} "
        f"{'vs flexmech':>12s}"
    )
    for name, balance, work, angle, steps, per_second in rows:
        print(
            f"  {name:40s} {balance:9.2e} {work:9.3f} {angle:10.4f} {steps:6d} {per_second:13.3f} "
            f"{per_second / rows[0][5]:11.2f}x"
        )
    print(
        f"  flexmech: its window compiled once in {compiled:.1f} s (its kernels are the rod's, the same element "
        f"family), engine built in {built:.2f} s"
    )
    accurate = [row for row in rows[2:] if row[1] <= rows[0][1]]
    if accurate:
        print(
            f"  the first Exudyn run with flexmech's energy balance ({accurate[0][0]}) takes "
            f"{accurate[0][5] / rows[0][5]:.2f}x flexmech's warm time"
        )


if __name__ == "__main__":
    # a cache of its own: "interpreted" means no compiled kernel, the kernels compiled here are timed
    os.environ.setdefault("FLEXMECH_CACHE_DIR", tempfile.mkdtemp(prefix="flexmech-bench-"))
    import exudyn

    print(f"exudyn {exudyn.__version__}; flexmech cache {os.environ['FLEXMECH_CACHE_DIR']}")
    # first both examples on interpreted kernels (they share their element family: compiling it
    # for one compiles it for the other)
    interpreted_rod, _ = flexmech_run(document("rod_free_vibration.json"), until=ROD_UNTIL, every=1)
    interpreted_bar, _ = flexmech_run(document("four_bar_dynamics.json"), until=BAR_UNTIL, every=1)
    rod(interpreted_rod)
    four_bar(interpreted_bar)
