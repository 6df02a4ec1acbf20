"""Exudyn's ANCFCable2D element as a second peer for benchmarks/work_precision.py (the rod).

    pip install exudyn            # the peer (written against exudyn 1.13)
    python -m benchmarks.exudyn_ancf

The physics of work_precision's rod (examples/rod_free_vibration.json) without shear, which the
element does not have: a straight steel rod from (0, 0) to (1.11, 0) m, b = 0.0127 m, h = 0.0032 m
(A = b h, I = b h^3 / 12), E = 200 GPa, 7850 kg/m^3, no gravity; ANCFCable2D elements (2 nodes of
NodePoint2DSlope1: position and slope r' per node, cubic Hermite interpolation, Euler-Bernoulli:
axial strain |r'| - 1 and the material curvature, Gauss-integrated) built by
exudyn.beams.GenerateBeamElementsAlongLine (GenerateStraightLineANCFCable2D is deprecated in 1.13).
Mass: the element's own, the consistent translational mass int rho A S^T S dx; it has no rotary
inertia (the GE element and flexmech carry rho I, whose relative effect on the period is of order
h^2 / (12 L^2)). Clamp at x = 0: coordinate constraints on the first node's position and
on the y component of its slope, r'_y = 0; r'_x, the stretch at the root, stays free, as the GE
element's axial strain does at its clamped node (constraining r'_x too moves the 64-element
0.125 ms run by 4e-9 in the period and 4e-6 in the tip history).

One model per run: the tip force (7.919276, 10.998155) N on a LoadForceVector at the last node;
SolveStatic with 20 load steps (the tip goes to (1.01771, 0.40607) m); the static state copied to
the initial configuration (systemData.SetSystemState), the load vector set to zero, and
SolveDynamic from that shape at rest: Exudyn's generalized-alpha, spectral radius 0.95, fixed
steps. Settings as work_precision.exudyn_run's: benchmarks.exudyn_peer._settings, dense linear
solver at 16 elements or fewer, EigenSparse with reuseAnalyzedPattern above, Newton tolerances of
the time integration relative 1e-6 and absolute 1e-8 N (the static solve keeps its own
defaults), one thread; the tip's position by a node sensor every step (kept in memory). Cost: wall seconds per simulated second of a whole run (model
build, Assemble, static solve and dynamic solve), cold (the first run of the configuration in the
process) and warm (the fastest of three repeats at once). Unlike work_precision.exudyn_run, whose warm
time is the dynamic solve alone, the warm time here counts the build and the static solve too.

Measured on 2026-11-28 (python -m benchmarks.exudyn_ancf; tip-history deviation from the
64-element 0.125 ms run, over the tip's largest motion):

    configuration          period s   history dev  cold s/s  warm s/s
    ANCF  16 el @ 0.500 ms  0.4715315     7.81e-04     0.191     0.191
    ANCF  32 el @ 0.500 ms  0.4715438     7.76e-04     0.297     0.299
    ANCF  64 el @ 0.500 ms  0.4715302     7.49e-04     0.702     0.694
    ANCF  64 el @ 0.125 ms  0.4715300     0.00e+00     1.099     1.083

    ANCF 64 el @ 0.125 ms (period 0.4715300 s) against Exudyn 256 GE @ 0.125 ms (period 0.4715317 s):
    3.6e-06 (period), 3.4e-05 (tip history)

The first period agrees with the GE element's (shear and rotary inertia included) to 3.6e-6, inside
the 1e-5 that the missing shear may account for. The step dominates the 0.5 ms rows: their tip
history deviation hardly depends on the element count, and their period moves by up to 3e-5
between element counts and with the Newton tolerances (64 elements: 3e-5 with ten times tighter
ones). The history converges about linearly in the step, alike for all three generalized-alpha
runs (rho_inf 0.95): against a 0.03125 ms run, 32 ANCF elements deviate 7.9e-4, 3.8e-4, 1.7e-4,
7.4e-5 at 0.5, 0.25, 0.125, 0.0625 ms, 32 GE elements 8.4e-4, 3.8e-4, 2.0e-4, 6.7e-5; flexmech's
8 cubic elements, against its sdirk4 reference, 7.6e-4, 4.2e-4, 1.5e-4 at 0.5, 0.25, 0.125 ms.
"""

from __future__ import annotations

import time

import exudyn as exu
import exudyn.itemInterface as eii
import numpy as np
from exudyn.beams import GenerateBeamElementsAlongLine

from benchmarks.exudyn_peer import ROD, ROD_TIP_FORCE, _settings
from benchmarks.work_precision import RHO_INF, WARM_REPEATS, errors, first_period

DENSE_UP_TO = 16  # elements: Exudyn's dense solver is faster up to here, EigenSparse above
LOAD_STEPS = 20  # of the static solve


def _model(elements: int) -> tuple:
    """(container, mbs, tip load, tip sensor) of the clamped rod with the tip force on."""
    container = exu.SystemContainer()
    mbs = container.AddSystem()
    A, I = ROD["b"] * ROD["h"], ROD["b"] * ROD["h"] ** 3 / 12
    cable = eii.ObjectANCFCable2D(
        massPerLength=ROD["rho"] * A, bendingStiffness=ROD["E"] * I, axialStiffness=ROD["E"] * A
    )
    rod = GenerateBeamElementsAlongLine(
        mbs,
        [0.0, 0.0, 0.0],
        [ROD["L"], 0.0, 0.0],
        elements,
        cable,
        groundConstraintsStart=[True, True, False, True],  # x, y, (r'_x free), r'_y
    )
    tip = rod["nodes"][-1]
    marker = mbs.AddMarker(eii.MarkerNodePosition(nodeNumber=tip))
    load = mbs.AddLoad(eii.LoadForceVector(markerNumber=marker, loadVector=[*ROD_TIP_FORCE, 0.0]))
    sensor = mbs.AddSensor(
        eii.SensorNode(
            nodeNumber=tip, outputVariableType=exu.OutputVariableType.Position, writeToFile=False, storeInternal=True
        )
    )
    return container, mbs, load, sensor


def _simulation_settings(elements: int, step: float, until: float, rel_tol: float, abs_tol: float):
    s = _settings(step, until, RHO_INF, rel_tol, abs_tol)
    if elements <= DENSE_UP_TO:
        s.linearSolver.solverType = exu.LinearSolverType.EXUdense
    else:
        s.linearSolver.reuseAnalyzedPattern = True
    s.parallel.numberOfThreads = 1
    s.staticSolver.numberOfLoadSteps = LOAD_STEPS
    return s


def _run_once(elements: int, step: float, until: float, rel_tol: float, abs_tol: float) -> tuple:
    """(wall seconds, times, tip (x, y)) of one whole run: build, static solve, release."""
    started = time.perf_counter()
    _container, mbs, load, sensor = _model(elements)  # the container keeps mbs alive
    mbs.Assemble()
    settings = _simulation_settings(elements, step, until, rel_tol, abs_tol)
    if not mbs.SolveStatic(settings, showHints=False, showCausingItems=False):
        raise RuntimeError("Exudyn static solver failed")
    bent = mbs.systemData.GetSystemState()  # the deflected shape, at rest
    mbs.systemData.SetSystemState(bent, configuration=exu.ConfigurationType.Initial)
    mbs.SetLoadParameter(load, "loadVector", [0.0, 0.0, 0.0])  # released at t = 0
    if not mbs.SolveDynamic(settings, showHints=False, showCausingItems=False):
        raise RuntimeError("Exudyn dynamic solver failed")
    wall = time.perf_counter() - started
    data = mbs.GetSensorStoredData(sensor)
    return wall, data[:, 0], data[:, 1:3]


def _sampled(times: np.ndarray, tip: np.ndarray, until: float, sample: float) -> np.ndarray:
    """The tip at every `sample` (the steps divide it: no interpolation)."""
    wanted = np.arange(0.0, until + 1e-12, sample)
    at = np.minimum(np.searchsorted(times, wanted - 1e-9), len(times) - 1)
    assert np.allclose(times[at], wanted, atol=1e-9), "a step that does not divide the sample time"
    return tip[at]


def ancf_rod_run(
    elements: int,
    step: float,
    until: float = 0.8,
    sample: float = 2e-3,
    rel_tol: float = 1e-6,
    abs_tol: float = 1e-8,
) -> dict:
    """The rod in `elements` ANCFCable2D elements at a fixed `step` (see the module docstring):
    the tip every `sample` s, its first period, and cold and warm wall seconds per simulated second."""
    timings = []
    for _ in range(1 + WARM_REPEATS):  # cold, then warm: the whole run again
        wall, times, tip = _run_once(elements, step, until, rel_tol, abs_tol)
        timings.append(wall)
    return {
        "tip": _sampled(times, tip, until, sample),
        "period": first_period(times, tip[:, 1]),
        "cold": timings[0] / until,
        "warm": min(timings[1:]) / until,
    }


def main() -> None:
    from benchmarks.work_precision import exudyn_run

    print(
        f"model: clamped steel rod (rod_free_vibration.json without shear), ANCFCable2D, released at t = 0, "
        f"generalized-alpha rho_inf {RHO_INF}, until 0.8 s (exudyn {exu.__version__})"
    )
    configurations = ((16, 5e-4), (32, 5e-4), (64, 5e-4), (64, 1.25e-4))
    runs = {c: ancf_rod_run(*c) for c in configurations}
    reference = runs[64, 1.25e-4]
    print("configuration          period s   history dev  cold s/s  warm s/s")
    for (elements, step), run in runs.items():
        history = errors(run, reference)[1]
        print(
            f"ANCF {elements:3d} el @ {step * 1e3:5.3f} ms  {run['period']:.7f}  {history:11.2e}  "
            f"{run['cold']:8.3f}  {run['warm']:8.3f}"
        )
    ge = exudyn_run(256, 1.25e-4)
    period_gap, history_gap = errors(reference, ge)
    print(
        f"ANCF 64 el @ 0.125 ms (period {reference['period']:.7f} s) against Exudyn 256 GE @ 0.125 ms "
        f"(period {ge['period']:.7f} s): {period_gap:.1e} (period), {history_gap:.1e} (tip history)"
    )


if __name__ == "__main__":
    main()
