"""Speed of the seed-002 cantilever (Sec. 2.5.1: EI = 0.08 N m^2, L = 101.6 mm, tip force
15 N perpendicular to the undeformed beam), side by side in one run, each solved to 1e-9
relative against Frisch-Fay's elliptic-integral solution:

  flexmech, warm: the link document compiled once; (a) the compiled fast path (fast_newton
      generated to C), (b) the plain Python Newton (service.solve_equilibrium), each from
      the undeformed state, as a design loop or a sweep calls them;
  peer: scipy.integrate.solve_bvp on theta'' = -(F L^2 / EI) cos(theta) with x, y as extra
      states, tol 1e-9, from the straight beam on an 11-point mesh.

Prints the accuracy each reaches, medians and the ratios. Run from the repository root:

    python3 -m benchmarks.elastica [--repeats N]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np
from scipy.integrate import solve_bvp

from flexmech.models import compile_mechanism, load_document
from flexmech.service import NewtonOptions, solve_equilibrium
from flexmech.service.solvers.fastpath import FastPath
from tests.elastica_oracles import cantilever_tip

EI, L, F = 0.08, 0.1016, 15.0
DOCUMENT = {
    "name": "cantilever (seed 002 Sec. 2.5.1)",
    "units": {"length": "m", "force": "N", "stress": "Pa", "angle": "rad"},
    "materials": {"m": {"E": EI / 1e-9}},
    "sections": {"s": {"shape": "general", "I": 1e-9}},
    "bodies": {"ground": {"fixed": True, "position": [0, 0]}, "tip": {"position": [L, 0]}},
    "elements": {"beam": {"type": "link", "from": "ground", "to": "tip", "length": L, "material": "m", "section": "s"}},
    "loads": {"F": {"type": "force", "body": "tip", "force": [0, F]}},
}


def median_seconds(fn, repeats: int) -> float:
    fn()  # warm
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        fn()
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def scipy_peer(tol: float = 1e-9):
    """(x_tip, y_tip, rotation) by solve_bvp; state (theta, theta', x/L, y/L) in u = s / L."""
    load = F * L**2 / EI

    def rhs(u, s):
        return np.vstack([s[1], -load * np.cos(s[0]), np.cos(s[0]), np.sin(s[0])])

    def bc(a, b):
        return np.array([a[0], b[1], a[2], a[3]])

    mesh = np.linspace(0, 1, 11)
    solution = solve_bvp(rhs, bc, mesh, np.zeros((4, mesh.size)), tol=tol, max_nodes=100000)
    if not solution.success:
        raise RuntimeError(solution.message)
    end = solution.sol(1.0)
    return L * end[2], L * end[3], end[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=200)
    args = parser.parse_args()

    exact = np.array(cantilever_tip(EI, L, F))
    mech = compile_mechanism(load_document(DOCUMENT))
    names = ("elements.beam.x_end", "elements.beam.y_end", "elements.beam.rotation_end")
    fast = FastPath(mech, outputs=names)
    p = mech.p()
    to_doc = np.array([1 / mech.nd_per_doc("length")] * 2 + [1.0])

    def flexmech_fast():
        z, _ = fast.solve(p)
        return z

    z = flexmech_fast()
    fast_tip = (
        np.asarray(mech.graphs.outputs(z, p)).ravel()[[mech.graphs.output_names.index(n) for n in names]] * to_doc
    )
    options = NewtonOptions(tol_residual=1e-12)
    plain = solve_equilibrium(mech, options)
    out = plain.outputs()
    plain_tip = np.array([out[n] for n in names])
    peer_tip = np.array(scipy_peer())

    def error(tip):
        return float(np.max(np.abs(tip - exact) / np.abs(exact)))

    rows = [
        (
            "flexmech fast path (compiled)" if fast.compiled else "flexmech fast path (VM)",
            flexmech_fast,
            error(fast_tip),
        ),
        ("flexmech service.solve_equilibrium", lambda: solve_equilibrium(mech, options, check=False), error(plain_tip)),
        ("scipy solve_bvp (tol 1e-9)", scipy_peer, error(peer_tip)),
    ]
    times = {
        label: median_seconds(fn, args.repeats if "scipy" not in label else max(args.repeats // 4, 20))
        for label, fn, _ in rows
    }
    peer = times[rows[-1][0]]
    print(
        f"cantilever EI={EI} N m^2, L={L} m, F={F} N; exact tip x={exact[0]:.12g} m, y={exact[1]:.12g} m, "
        f"rotation={math.degrees(exact[2]):.12g} deg"
    )
    print(f"{'solver':40s} {'max rel. error':>15s} {'median':>12s} {'peer / this':>12s}")
    for label, _, err in rows:
        print(f"{label:40s} {err:15.2e} {times[label] * 1e3:10.3f} ms {peer / times[label]:11.1f}x")


if __name__ == "__main__":
    main()
