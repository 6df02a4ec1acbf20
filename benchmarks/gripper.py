"""Speed of the seed-000 gripper, side by side in one run:

(a) one warm equilibrium solve (F = 50 uN, from the undeformed state) and
(b) the 100-step opening-closing sweep (F from -60 uN to the closing force, continuation,
    giving the configuration and the end-effector trajectory at every point),

through flexmech's compiled fast path, its plain Python API (service.solve_equilibrium /
service.solvers.sweep), and the peer: scipy.optimize.root (hybr, finite-difference Jacobian) on the
same residual written in numpy. Prints medians and ratios; run as a script:

    python3 benchmarks/gripper.py [--model partial_nonlinear|linear] [--repeats N] [--sweep-repeats N]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np
from scipy.optimize import root

from flexmech.models import compile_mechanism, load_document
from flexmech.service import NewtonOptions, solve_equilibrium, solve_for_target, sweep
from flexmech.service.solvers.fastpath import FastPath

try:
    from benchmarks.numpy_peer import NumpyGripperResidual
except ImportError:  # run as a script from the repository root
    from numpy_peer import NumpyGripperResidual

ACTUATION = "/loads/actuation/force/1"
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "gripper.json"


def median_seconds(fn, repeats: int) -> float:
    fn()  # warm
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="partial_nonlinear", choices=["linear", "partial_nonlinear"])
    parser.add_argument("--repeats", type=int, default=200, help="timed single solves (x10 for the fast path)")
    parser.add_argument(
        "--sweep-repeats", type=int, default=None, help="timed sweeps (default: repeats / 20, at least 5)"
    )
    args = parser.parse_args()

    mech = compile_mechanism(load_document(EXAMPLE), model=args.model).with_values({ACTUATION: 50.0})
    closing = solve_for_target(mech, ACTUATION, "end_effector.x", 0.0).value
    values = np.linspace(-60.0, closing, 101)  # 100 steps
    fast = FastPath(mech, outputs=("end_effector.x", "end_effector.y"))  # the trajectory
    peer = NumpyGripperResidual(mech)
    p = mech.p()
    z0 = np.zeros(mech.n_free)
    P = fast.path_parameters(ACTUATION, values)

    def peer_sweep():
        z = z0
        out = []
        for column in P.T:
            peer.set_parameters(column)
            sol = root(peer, z, method="hybr", tol=1e-12)
            z = sol.x
            out.append(z)
        peer.set_parameters(p)
        return np.array(out)

    # agreement before timing: all three solve the same problem
    z_fast, norm = fast.solve(p)
    z_api = solve_equilibrium(mech).z
    z_peer = root(peer, z0, method="hybr", tol=1e-12).x
    Z_fast, norms, _ = fast.sweep(P)
    Z_peer = peer_sweep()
    print(f"gripper ({args.model}), compiled: {fast.compiled}, closing force {closing:.4f} uN")
    print(
        f"max |z_fast - z_api| = {np.abs(z_fast - z_api).max():.2e}, "
        f"max |z_fast - z_scipy| = {np.abs(z_fast - z_peer).max():.2e} (nondim.), "
        f"sweep: max |Z_fast - Z_scipy| = {np.abs(Z_fast.T - Z_peer).max():.2e}, max residual {norms.max():.1e}"
    )

    r = args.repeats
    rs = args.sweep_repeats if args.sweep_repeats is not None else max(5, r // 20)
    single = {
        "flexmech fast path": median_seconds(lambda: fast.solve(p), 10 * r),
        "flexmech Python API": median_seconds(lambda: solve_equilibrium(mech), r),
        "scipy root (hybr, FD)": median_seconds(lambda: root(peer, z0, method="hybr", tol=1e-12), r),
    }
    sweeps = {
        "flexmech fast path": median_seconds(lambda: fast.sweep(P), r),
        "flexmech Python API": median_seconds(lambda: sweep(mech, ACTUATION, values, NewtonOptions()), rs),
        "scipy root (hybr, FD)": median_seconds(peer_sweep, rs),
    }
    peer_name = "scipy root (hybr, FD)"
    for title, table, unit, scale in (
        ("(a) warm single solve", single, "us", 1e6),
        ("(b) 100-step opening-closing sweep", sweeps, "ms", 1e3),
    ):
        print(f"\n{title}")
        for name, seconds in table.items():
            ratio = table[peer_name] / seconds
            print(f"  {name:24s} median {seconds * scale:10.2f} {unit}   scipy/this = {ratio:8.1f}x")


if __name__ == "__main__":
    main()
