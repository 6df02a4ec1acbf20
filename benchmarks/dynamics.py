"""Speed of time simulation against a peer at equal accuracy, side by side in one run
(Lan 2005 Ch. 4):

  Example I.1, the steel rod released from its held shape (tip at (1.0177, 0.4061) m), 5 s
      (about ten periods), no gravity. Measure: the period (mean over the run) within 1e-3 of
      the converged one, which the finest run here gives; the energy drift max |E/E0 - 1|
      is printed too.
  Example II.2, the four-bar under the moment of Eq. 4.5, 1.5 s. Measure: the energy
      balance max |T + U - W| / max W (kinetic, strain, work of the moment).

flexmech runs the examples' documents with slender-rod models: Euler-Bernoulli links
(shear and axial strain off: the rod's h/L is 0.003 and the links' r/L 0.02, so they change
the period by less than 1e-5; they also bring stiff modes that the step would have to
follow), cubic elements (the rod 3, the four-bar 1/4/2), generalized-alpha (rho_inf 1 for
the rod, 0.95 for the four-bar), fixed steps, the stepping compiled with the system C
compiler (built once per structure and cached; the build is timed apart). The times are the
integration's alone on both sides (not the static start, the model building or the report). The peer is Exudyn (benchmarks/exudyn_peer.py):
GeometricallyExactBeam2D elements (linear, with shear and axial strain), generalized-alpha
0.95, 1 ms steps, compiled C++. Each tool runs at the discretization it needs for the
measure, and both are printed with their figures.

The peer: pip install "flexmech[bench]" (exudyn). Run from the repository root:

    python3 -m benchmarks.dynamics
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from models import compile_mechanism, load_document
from service.dynamics.run import run_simulation, simulation_spec

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ROD_UNTIL, BAR_UNTIL = 5.0, 1.5


def slender(example: str, intervals: dict[str, int]):
    document = json.loads((EXAMPLES / example).read_text())
    for name, element in document["elements"].items():
        if element.get("type") == "link":
            element.update(shear=False, axial=False, intervals=intervals[name])
    return compile_mechanism(load_document(document))


def flexmech_run(mech, **fields) -> tuple[dict, float, float]:
    """(report, seconds of the integration alone, seconds of the warm-up that builds and
    compiles). Like the peer's, the timed part leaves out the static start and the report."""
    started = time.perf_counter()
    run_simulation(mech, simulation_spec(mech, {**fields, "until": 20 * fields["step"]}))
    built = time.perf_counter() - started
    _, report = run_simulation(mech, simulation_spec(mech, fields))
    return report, report["seconds"], built


def period_and_drift(times, tip_y, kinetic, potential) -> tuple[float, float]:
    t, y = np.asarray(times), np.asarray(tip_y)
    crossings = np.array([t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
                          for i in range(len(y) - 1) if y[i] > 0 >= y[i + 1]])
    energy = np.asarray(kinetic) + np.asarray(potential)
    return float(np.mean(np.diff(crossings))), float(np.abs(energy / energy[0] - 1).max())


def rod() -> None:
    from benchmarks.exudyn_peer import rod_free_vibration

    rows = []
    fine = slender("rod_free_vibration.json", {"rod": 8})
    report, wall, _ = flexmech_run(fine, until=ROD_UNTIL, step=0.0005, every=1, adaptive=False)
    reference, _ = period_and_drift(report["times"], report["outputs"]["bodies.tip.y"],
                                    report["energies"]["kinetic"], report["energies"]["potential"])
    mech = slender("rod_free_vibration.json", {"rod": 3})
    report, wall, built = flexmech_run(mech, until=ROD_UNTIL, step=0.002, every=1, compiled=True, adaptive=False,
                                       rho_inf=1.0)
    rows.append(("flexmech 3 cubic, h = 2 ms", *period_and_drift(
        report["times"], report["outputs"]["bodies.tip.y"], report["energies"]["kinetic"],
        report["energies"]["potential"]), wall / ROD_UNTIL))
    for elements in (16, 32):
        peer = rod_free_vibration(elements=elements, step=1e-3, until=ROD_UNTIL, rho_inf=0.95)
        rows.append((f"Exudyn {elements} linear, h = 1 ms", peer["period"], peer["energy_drift"],
                     peer["wall_seconds"] / ROD_UNTIL))
    print(f"Example I.1, {ROD_UNTIL:g} s; reference period {reference:.5f} s (flexmech, 8 cubic, h = 0.5 ms)")
    print(f"  {'run':30s} {'period s':>9s} {'error':>9s} {'drift':>9s} {'wall s per s':>13s}")
    for name, period, drift, per_second in rows:
        print(f"  {name:30s} {period:9.5f} {abs(period / reference - 1):9.1e} {drift:9.1e} {per_second:13.3f}")
    print(f"  flexmech's build and compile (once per structure, cached): {built:.1f} s")
    accurate = [row for row in rows[1:] if abs(row[1] / reference - 1) <= 1e-3]
    if accurate and abs(rows[0][1] / reference - 1) <= 1e-3:
        print(f"  at the period to 1e-3: Exudyn takes {accurate[0][3] / rows[0][3]:.1f}x flexmech's time "
              f"(energy drift {accurate[0][2] / rows[0][2]:.2f}x flexmech's)")


def four_bar() -> None:
    from benchmarks.exudyn_peer import four_bar as peer_four_bar

    mech = slender("four_bar_dynamics.json", {"crank": 1, "coupler": 4, "follower": 2})
    report, wall, built = flexmech_run(mech, until=BAR_UNTIL, step=0.003, every=1, compiled=True, adaptive=False)
    peer = peer_four_bar(elements=(8, 16, 16), step=1e-3, until=BAR_UNTIL, rho_inf=0.95)
    print(f"\nExample II.2, {BAR_UNTIL:g} s")
    print(f"  {'run':30s} {'balance':>9s} {'work J':>8s} {'steps':>6s} {'wall s per s':>13s}")
    print(f"  {'flexmech 1/4/2 cubic, h = 3 ms':30s} {report['energy_balance_error']:9.2e} "
          f"{report['energies']['input_work'][-1]:8.2f} {report['steps']:6d} {wall / BAR_UNTIL:13.3f}")
    print(f"  {'Exudyn 8/16/16 linear, h = 1 ms':30s} {peer['balance_error']:9.2e} {peer['input_work'][-1]:8.2f} "
          f"{len(peer['times']) - 1:6d} {peer['wall_seconds'] / BAR_UNTIL:13.3f}")
    print(f"  flexmech's build and compile (once per structure, cached): {built:.1f} s")
    print(f"  Exudyn takes {peer['wall_seconds'] / wall:.1f}x flexmech's time "
          f"(balance {peer['balance_error'] / report['energy_balance_error']:.1f}x flexmech's)")


if __name__ == "__main__":
    rod()
    four_bar()
