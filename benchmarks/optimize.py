"""Speed of the 1-term grasper shape optimization (seed 002 Sec. 5.6.1, Table 5.8), side by
side in one run:

  flexmech: examples/grasper_shape.json, one NLP over (L, c1) and the link's shooting
      unknowns, IPOPT with exact derivatives. Cold: the first call in the process (graphs and
      the NLP built); warm: later calls (the design loop of a tool calling the service).
  peer: scipy.optimize.minimize (SLSQP) over (L, c1) with finite-difference gradients; each
      objective is a single-shooting solve of the clamped-clamped elastica (scipy fsolve on
      the base force and moment, solve_ivp DOP853 at rtol 1e-10), warm-started from the
      previous solve; the undeformed tip x = L * integral(cos eta) by quad as the equality.

Prints both optima (they must agree), medians and the ratio. Run from the repository root:

    python3 -m benchmarks.optimize [--repeats N]
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import time
from pathlib import Path

import numpy as np
from scipy.integrate import quad, solve_ivp
from scipy.optimize import fsolve, minimize

from flexmech.models import compile_mechanism
from flexmech.models.documents.document import parse_document
from flexmech.service.design.optimize import optimize
from flexmech.service.design.problem import design_problem

DOCUMENT = Path(__file__).resolve().parents[1] / "examples" / "grasper_shape.json"
E, W, H = 2.62e9, 0.04572, 0.001016
EI = E * W * H**3 / 12
X_TIP, DY, L_MAX = 0.0508, 0.0127, 0.085


class ShootingPeer:
    """The tip force of a clamped-clamped link pushed by DY, by single shooting."""

    def __init__(self):
        self.guess = np.array([0.0, 5.0, 0.0])  # base force H, V and moment M0

    @staticmethod
    def undeformed_tip_x(L: float, c1: float) -> float:
        return L * quad(lambda u: math.cos(c1 * math.sin(2 * math.pi * u)), 0, 1, epsabs=1e-13)[0]

    def tip_force(self, design: np.ndarray) -> float:
        L, c1 = design
        x_target = self.undeformed_tip_x(L, c1)

        def rhs(u, s, Hf, V):
            theta, M, _, _ = s
            eta_prime = c1 * 2 * math.pi * math.cos(2 * math.pi * u)
            return [
                eta_prime + L * M / EI,
                L * (-V * math.cos(theta) + Hf * math.sin(theta)),
                L * math.cos(theta),
                L * math.sin(theta),
            ]

        def mismatch(unknowns):
            Hf, V, M0 = unknowns
            end = solve_ivp(rhs, (0, 1), [0.0, M0, 0.0, 0.0], args=(Hf, V), method="DOP853", rtol=1e-10, atol=1e-12).y[
                :, -1
            ]
            return [end[0], end[2] - x_target, end[3] - DY]

        self.guess = fsolve(mismatch, self.guess, xtol=1e-12)
        return float(self.guess[1])

    def optimize(self, start: np.ndarray):
        constraint = {"type": "eq", "fun": lambda d: self.undeformed_tip_x(*d) - X_TIP}
        return minimize(
            self.tip_force,
            start,
            method="SLSQP",
            bounds=[(X_TIP, L_MAX), (0, 2)],
            constraints=[constraint],
            options={"ftol": 1e-10, "maxiter": 200},
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20)
    args = parser.parse_args()
    document = parse_document(json.loads(DOCUMENT.read_text()))
    start = np.array([0.08, 1.2])

    began = time.perf_counter()
    problem = design_problem(compile_mechanism(document), document.optimize)
    result = optimize(problem)
    cold = time.perf_counter() - began
    warm = []
    for _ in range(args.repeats):
        began = time.perf_counter()
        result = optimize(design_problem(compile_mechanism(document), document.optimize))
        warm.append(time.perf_counter() - began)
    ours = result.best.design

    peer_times, peer = [], None
    for _ in range(max(3, args.repeats // 4)):
        shooting = ShootingPeer()
        began = time.perf_counter()
        peer = shooting.optimize(start)
        peer_times.append(time.perf_counter() - began)

    print("1-term grasper shape optimization (seed 002 Table 5.8: c1 = 1.3426, L on its bound 0.085 m)")
    print(f"{'solver':<46} {'L [m]':>10} {'c1':>10} {'F [N]':>10} {'median [s]':>11}")
    print(
        f"{'flexmech (IPOPT, exact derivatives), warm':<46} {ours['/elements/link/length']:>10.6f} "
        f"{ours['/elements/link/shape/coefficients/0']:>10.6f} {result.best.objective:>10.6f} "
        f"{statistics.median(warm):>11.4f}"
    )
    print(f"{'flexmech, cold (graphs and NLP built)':<46} {'':>10} {'':>10} {'':>10} {cold:>11.4f}")
    print(
        f"{'scipy SLSQP, FD gradients over shooting':<46} {peer.x[0]:>10.6f} {peer.x[1]:>10.6f} "
        f"{peer.fun:>10.6f} {statistics.median(peer_times):>11.4f}"
    )
    print(f"SLSQP: {peer.nfev} objective evaluations, {peer.nit} iterations, success {peer.success}")
    print(
        f"speed-up, flexmech warm vs SLSQP: {statistics.median(peer_times) / statistics.median(warm):.1f}x; "
        f"cold vs SLSQP: {statistics.median(peer_times) / cold:.2f}x"
    )
    print(
        f"difference in c1: {abs(peer.x[1] - ours['/elements/link/shape/coefficients/0']):.2e}, "
        f"in F: {abs(peer.fun - result.best.objective) / result.best.objective:.2e} relative"
    )


if __name__ == "__main__":
    main()
