"""How fast can a time integrator's tip-history error fall on the released rod of
benchmarks/work_precision.py? An independent check, by linear modal analysis and no time
integration (issue 50, Acceptance 2).

    python -m benchmarks.release_spectrum

Released from its static shape at rest, the rod moves as the sum of its natural modes, each with
the share of the static tip deflection that the shape puts in it. A step h that does not resolve
a mode (omega h > 1) gets it wrong whatever the scheme's order: an L-stable scheme removes it,
generalized-alpha keeps it with the wrong phase. So the tip-history error cannot fall faster than
the share of the modes above 1 / h, until h resolves every mode that carries more than the
target. This prints the modes (cubic elements, shear and axial strain, kappa 5/6, about the
straight rod: the release's large deflection shifts the frequencies, not the decay of the shares)
and that tail against h.

Measured 2026-11-28 (16 elements): the shares fall as omega^-2 (mode 4, counted from 0: 3.0e-4
at 756 rad/s; mode 6: 6.9e-5 at 1577 rad/s), so the tail above 1 / h falls as h^1.1 to h^2.2
between 2.5 and 0.3125 ms (1.4e-3, 3.2e-4, 1.2e-4, 5.6e-5): a fifth-order Radau IIA measures orders 1.2 to 2.2 on
the tip history in that range (4 elements against its own 0.3125 ms run: 1.8e-3, 4.3e-4, 1.9e-4,
6.9e-5, 1.6e-5 at 10, 5, 2.5, 1.25, 0.625 ms), not 5. An observed order of 4 on the tip history
needs a release whose spectrum is bounded (a smooth release; tests/dynamics/test_sdirk.py and
test_radau.py measure the schemes' orders so).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

ROD_DOCUMENT = Path(__file__).resolve().parents[1] / "examples" / "rod_free_vibration.json"
SCALE = 1e-4  # of the hold force: small enough for the static shape to be linear in it
TIP_Y = 1  # the tip body's y among the energy form's unknowns


def modal_shares(intervals: int) -> tuple[np.ndarray, np.ndarray]:
    """(omega rad/s, each mode's share of the static tip deflection), ascending in omega."""
    import flexmech
    from flexmech.service.dynamics.histories import read_histories
    from flexmech.service.dynamics.modes import form_of, natural_modes
    from flexmech.service.dynamics.run import simulation_spec, start_shape

    document = json.loads(ROD_DOCUMENT.read_text())
    document["elements"]["rod"]["intervals"] = intervals
    document["sections"]["rod"]["shear_factor"] = 5.0 / 6.0
    document["loads"]["hold"]["force"] = [SCALE * f for f in document["loads"]["hold"]["force"]]
    mech = flexmech.load(document)
    spec = simulation_spec(mech)
    histories = read_histories(mech, spec.histories, spec.until, "/simulate/histories")
    x0, _ = start_shape(mech, spec, histories)
    released = histories.at(mech.p(), spec.until)[0]
    form = form_of(mech.structure)
    straight = np.zeros_like(x0)
    modes = natural_modes(mech.structure, released, straight, np.zeros(form.n_equalities))
    mass = np.asarray(form.mass(straight, released), dtype=float)
    contributions = modes.shapes[TIP_Y, :] * (modes.shapes.T @ mass @ x0)
    return modes.omegas, contributions / contributions.sum()


def main() -> None:
    omegas, shares = modal_shares(16)
    print("rod of examples/rod_free_vibration.json, 16 cubic elements, kappa 5/6, modes about the straight rod")
    print("mode  omega rad/s  period ms  share of the tip's deflection")
    for k in range(14):
        print(f"{k:4d}  {omegas[k]:11.4g}  {2e3 * np.pi / omegas[k]:9.4g}  {shares[k]:10.3e}")
    print("\nstep ms  share of the modes with omega h > 1  (the least tip-history error of any scheme)")
    previous = None
    for h in (1e-2, 5e-3, 2.5e-3, 1.25e-3, 6.25e-4, 3.125e-4):
        tail = float(np.abs(shares[omegas * h > 1.0]).sum())
        rate = f"   h^{np.log2(previous / tail):.2f}" if previous else ""
        print(f"{h * 1e3:7.4g}  {tail:10.3e}{rate}")
        previous = tail


if __name__ == "__main__":
    main()
