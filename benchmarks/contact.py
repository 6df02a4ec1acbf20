"""Speed of gripping contact (Lan 2005 Ch. 6, Example I: the jaw against the circular
fixture, geometry of the reading notes, examples/gripper_jaw_contact.json), side by side in
one run:

  flexmech: 8 cubic elements (the insertion force converged to about 1e-9 relative against
      16; the peer's error is printed beside it), built once; (a) one state warm: the
      state at x_o = 67.81 mm solved from the path's previous state (x_o = 68.16 mm: IPOPT
      warm start, Newton on the active set, friction), frictionless and mu = 0.5; (b) the
      whole 101-state insertion (x_o from 80 to 45 mm), each state from the one before;
  peer: the thesis' method, its discretization (Eqs. 6.11-6.16, 6.20: nodal angles,
      trapezoidal positions, N = 400 intervals, M = 100 points on the face) by scipy's
      SLSQP with exact vectorized gradients (benchmarks/thesis_slsqp.py), from the
      neighbouring state's angles (it gains nothing from that: SLSQP restarts its BFGS).

Prints each method's insertion force at x_o = 67.81 mm against 16 cubic elements, the
medians and the ratios. Run from the repository root:

    python3 -m benchmarks.contact [--repeats N]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

from benchmarks.thesis_slsqp import example_one_state
from flexmech.models import compile_mechanism, load_document
from flexmech.service.contact.path import follow, parameters_at, path_fields
from flexmech.service.contact.problem import contact_problem
from flexmech.service.contact.report import friction_coefficients, pairs_report
from flexmech.service.contact.solve import ContactOptions, solve_state

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "gripper_jaw_contact.json"
STATE, BEFORE = 67.81, 68.16  # mm


def example(mu: float, intervals: int = 8) -> dict:
    doc = json.loads(EXAMPLE.read_text())
    doc["contacts"]["pairs"]["insertion"]["friction"] = mu
    doc["elements"]["finger"]["intervals"] = intervals
    return doc


class Flexmech:
    def __init__(self, mu: float, intervals: int = 8):
        self.mech = compile_mechanism(load_document(example(mu, intervals)))
        self.problem = contact_problem(self.mech.structure)
        self.fields = path_fields(
            self.mech, [p.model_dump(exclude_none=True) for p in self.mech.document.contacts.path.parameters]
        )

    def sweep(self) -> tuple[float, list]:
        started = time.perf_counter()
        states = list(
            follow(self.mech, self.problem, self.fields, list(range(self.fields.states)), None, ContactOptions())
        )
        return time.perf_counter() - started, states

    def state_after(self, x_before: float, x: float):
        """(the state at x from the path state at x_before, seconds of that last solve)."""
        path = path_fields(self.mech, [{"path": self.fields.pointers[0], "values": [80.0, x_before, x]}])
        states = [s for _, s in follow(self.mech, self.problem, path, [0, 1], None, ContactOptions())]
        p = parameters_at(self.mech, path, 2)
        started = time.perf_counter()
        state = solve_state(self.problem, p, friction_coefficients(self.mech, self.problem, p), states[-1])
        return state, time.perf_counter() - started

    def force_x(self, state) -> float:
        return pairs_report(self.mech, self.problem, state)["insertion"]["force"][0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20)
    repeats = parser.parse_args().repeats
    print(__doc__.split("\n\n")[0].replace("\n", " "))
    for mu in (0.0, 0.5):
        ours, reference = Flexmech(mu), Flexmech(mu, 16)
        ours.sweep()  # warm: solvers built
        sweep_seconds, states = ours.sweep()
        converged = sum(s.converged for _, s in states)
        times = [ours.state_after(BEFORE, STATE)[1] for _ in range(repeats)]
        state = ours.state_after(BEFORE, STATE)[0]
        truth = reference.force_x(reference.state_after(BEFORE, STATE)[0])
        print(f"\nmu = {mu}: insertion force at x_o = {STATE} mm (16 cubic elements: {truth:.9f} N)")
        print(
            f"  flexmech, 8 cubic elements: {ours.force_x(state):.9f} N (rel. error "
            f"{abs(ours.force_x(state) / truth - 1):.1e}), one state warm {1e3 * statistics.median(times):.2f} ms "
            f"(median of {repeats}); 101-state insertion {sweep_seconds:.3f} s ({converged} converged)"
        )
        if mu == 0.0:
            before = example_one_state(BEFORE, N=400, M=100)
            peer_times, peer = [], None
            for _ in range(3):
                peer = example_one_state(STATE, N=400, M=100, psi_start=before["psi"])
                peer_times.append(peer["seconds"])
            peer_force = peer.get("multiplier_force_x", peer["force_x"])
            ratio = statistics.median(peer_times) / statistics.median(times)
            print(
                f"  peer, thesis' method (SLSQP, N = 400, M = 100): {peer_force:.6f} N from its multipliers, "
                f"{peer['force_x']:.6f} N recovered from the clamp moment (Eq. 6.6) (rel. error "
                f"{abs(peer_force / truth - 1):.1e}), {1e3 * statistics.median(peer_times):.0f} ms, "
                f"{peer['iterations']} iterations, success {peer['success']}"
            )
            print(f"  ratio peer / flexmech (one state warm): {ratio:.0f}x")


if __name__ == "__main__":
    main()
