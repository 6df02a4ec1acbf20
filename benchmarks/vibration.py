"""Natural modes and frequency response: flexmech against Exudyn's eigenvalues, side by side in
one run, and the warm times of the gripper's modes and frequency response.

  The Table 4.1 rod (examples/rod_free_vibration.json, clamped, undeformed): its first five
      natural frequencies. flexmech: the document's 8 cubic elements (bending, shear with
      G = 80 GPa and kappa = 1, axial strain, rotary inertia rho I, consistent mass). Exudyn:
      n ObjectBeamGeometricallyExact2D elements (the same strains and inertia, linear
      interpolation, one-point strains; benchmarks/exudyn_peer.py), clamped by fixing the first
      node's coordinates, mbs.ComputeODE2Eigenvalues (dense; its matrices from the assembled
      system). Accuracy: each frequency against a converged one (flexmech with 32 cubic
      elements); same physics: the first period, 0.47221 s in Euler-Bernoulli theory.
      Cold: building the model (flexmech: compiling its graphs on an empty cache; Exudyn: the
      Python model and Assemble) and the first solve; warm: a repeated solve (median).
  The exact gripper with its flexures' mass (examples/gripper_modes.json): ten modes about
      the equilibrium under its load (the Newton solve included), and a 1000-point frequency
      response of the end effector to the actuation force (the grid refined at resonances
      adds points; modal superposition over every mode), warm, median of repeats.

The peer: pip install "flexmech[bench]" (exudyn). Run from the repository root:

    python3 -m benchmarks.vibration
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
COUNT = 5


def _median_ms(call, repeats: int = 30) -> float:
    call()
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        call()
        times.append(time.perf_counter() - started)
    return statistics.median(times) * 1e3


def _rod_document(intervals: int) -> dict:
    data = json.loads((EXAMPLES / "rod_free_vibration.json").read_text())
    data["elements"]["rod"]["intervals"] = intervals
    return data


def flexmech_rod(intervals: int) -> dict:
    from flexmech.models import compile_mechanism, load_document
    from flexmech.service.analyses import ANALYSES
    from flexmech.service.analyses.base import AnalysisRequest

    modes = ANALYSES.named("modes")
    request = AnalysisRequest(given={"count": COUNT, "at": "undeformed", "shapes": False})
    started = time.perf_counter()
    mech = compile_mechanism(load_document(_rod_document(intervals)))
    report = modes.run(mech, request)
    cold = time.perf_counter() - started
    warm = _median_ms(lambda: modes.run(mech, request))
    return {
        "model": f"{intervals} cubic elements (bending, shear, axial, rotary inertia), {report['unknowns']} unknowns",
        "frequencies": np.array([m["frequency"] for m in report["modes"]]),
        "cold_s": cold,
        "warm_ms": warm,
    }


def exudyn_rod(elements: int) -> dict:
    import exudyn as exu

    from benchmarks.exudyn_peer import ROD, _Link

    started = time.perf_counter()
    container = exu.SystemContainer()
    mbs = container.AddSystem()
    area, second = ROD["b"] * ROD["h"], ROD["b"] * ROD["h"] ** 3 / 12
    _Link(mbs, (0.0, 0.0), (ROD["L"], 0.0), elements, ROD["E"], ROD["G"], ROD["rho"], area, second)
    mbs.Assemble()

    def solve():
        values, _ = mbs.ComputeODE2Eigenvalues(
            numberOfEigenvalues=COUNT, constrainedCoordinates=[0, 1, 2], convert2Frequencies=True
        )
        return np.asarray(values)[:COUNT]

    frequencies = solve()
    cold = time.perf_counter() - started
    return {
        "model": f"{elements} GeometricallyExactBeam2D elements (bending, shear, axial, rotary inertia)",
        "frequencies": frequencies,
        "cold_s": cold,
        "warm_ms": _median_ms(solve, repeats=10),
    }


def gripper() -> dict:
    from flexmech.models import compile_mechanism, load_document
    from flexmech.service.analyses import ANALYSES
    from flexmech.service.analyses.base import AnalysisRequest

    mech = compile_mechanism(load_document(EXAMPLES / "gripper_modes.json"))
    modes = ANALYSES.named("modes")
    ten = AnalysisRequest(given={"count": 10, "shapes": False})
    response = ANALYSES.named("frequency_response")
    sweep = AnalysisRequest(
        given={"input": "/loads/actuation/force/1", "outputs": ["end_effector.x"], "points": 1000, "stop": 2e5}
    )
    first = modes.run(mech, ten)
    curve = response.run(mech, sweep)
    return {
        "first": first["modes"][0]["frequency"],
        "tenth": first["modes"][-1]["frequency"],
        "points": len(curve["frequencies"]),
        "peaks": len(curve["resonances"]),
        "modes_ms": _median_ms(lambda: modes.run(mech, ten)),
        "response_ms": _median_ms(lambda: response.run(mech, sweep), repeats=10),
    }


def main() -> None:
    cache = tempfile.mkdtemp(prefix="flexmech-bench-cache-")
    os.environ["FLEXMECH_CACHE_DIR"] = cache  # cold: graphs built, not loaded
    try:
        reference = flexmech_rod(32)["frequencies"]
        rows = [("flexmech", flexmech_rod(8))]
        try:
            rows += [("exudyn", exudyn_rod(n)) for n in (16, 64, 256)]
        except ImportError:
            print("exudyn is not installed (pip install exudyn): its rows are left out")
        print("The Table 4.1 rod, clamped, undeformed: the first five natural frequencies (Hz)")
        print(f"  reference (flexmech, 32 cubic elements): {np.array2string(reference, precision=6)}")
        print(f"  Euler-Bernoulli's first period 0.47221 s; flexmech's converged: {1 / reference[0]:.6f} s")
        for name, row in rows:
            error = np.abs(row["frequencies"] / reference - 1)
            print(f"  {name}: {row['model']}")
            print(f"    frequencies {np.array2string(row['frequencies'], precision=6)}")
            print(f"    first period {1 / row['frequencies'][0]:.6f} s; largest relative error {error.max():.2e}")
            print(f"    cold {row['cold_s']:.3f} s, warm {row['warm_ms']:.3f} ms")
        found = gripper()
        print("The exact gripper with its flexures' mass (examples/gripper_modes.json), warm, median:")
        print(
            f"  ten modes about the loaded equilibrium ({found['first']:.1f} to {found['tenth']:.1f} Hz): {found['modes_ms']:.2f} ms"
        )
        print(
            f"  frequency response of end_effector.x, {found['points']} frequencies "
            f"(1000 log-spaced and those added at {found['peaks']} resonances): {found['response_ms']:.1f} ms"
        )
    finally:
        shutil.rmtree(cache, ignore_errors=True)


if __name__ == "__main__":
    main()
