"""Radau IIA collocation on the dense dynamics form (service.dynamics.radau), on the steel rod of
examples/rod_free_vibration.json released smoothly (its hold force decays as exp(-(t/50 ms)^2),
so the motion is smooth and a step-size study measures the scheme, not the release's jolt):

- against an independent scheme: its fine-step tip history is the shipped generalized-alpha's
  (element kernels, 0.25 ms steps) to the latter's own accuracy;
- its error falls at least eightfold per halved step (order >= 3: the stiff axial and shear
  modes following the load quasi-statically hold Radau IIA near its stage order 3, below its
  classical order 5), and it reaches 1e-4 of the motion at 10 ms steps, forty times the
  0.25 ms that second-order generalized-alpha needs for 2e-6."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import flexmech
from flexmech.service.dynamics.histories import read_histories
from flexmech.service.dynamics.radau import RadauStepper
from flexmech.service.dynamics.run import simulation_spec, start_shape

ROD = Path(__file__).resolve().parents[2] / "examples" / "rod_free_vibration.json"
UNTIL = 0.1  # s
FINE = 1.25e-3  # s, the reference step


@pytest.fixture(scope="module")
def rod():
    document = json.loads(ROD.read_text())
    document["elements"]["rod"]["intervals"] = 2
    hold = document["loads"]["hold"]["force"]
    document["simulate"]["histories"] = {f"/loads/hold/force/{k}": f"{hold[k]!r} * exp(-(t / 0.05)**2)" for k in (0, 1)}
    mech = flexmech.load(document)
    spec = simulation_spec(mech)
    histories = read_histories(mech, spec.histories, UNTIL, "/simulate/histories")
    x0, _ = start_shape(mech, spec, histories)
    stepper = RadauStepper(mech.structure, mech.p(), histories)
    tips = {}
    for h in (1e-2, 5e-3, FINE):
        run = stepper.run(x0, np.zeros_like(x0), UNTIL, h)
        assert run.status == "finished", run.message
        tip = np.array([x[:2] for x in run.positions]) / mech.nd_per_doc("length")  # tip.x, tip.y: m from rest
        tips[h] = (np.array(run.times), tip)
    return mech, tips


def _error(tips, h) -> float:
    """The largest tip deviation from the reference over the run, of the tip's largest motion."""
    ref_times, ref = tips[FINE]
    times, tip = tips[h]
    at = np.searchsorted(ref_times, times - 1e-12)
    return float(np.abs(tip - ref[at]).max() / np.abs(ref - ref[0]).max())


def test_radau_agrees_with_the_shipped_generalized_alpha(rod):
    mech, tips = rod
    report = flexmech.simulate(mech, until=UNTIL, step=2.5e-4, every=1)
    assert report["status"] == "finished"
    times = np.array(report["times"])
    rest = np.array([mech.value(f"/bodies/tip/position/{k}") for k in (0, 1)])
    alpha = np.c_[report["outputs"]["bodies.tip.x"], report["outputs"]["bodies.tip.y"]] - rest
    ref_times, ref = tips[FINE]
    at = np.searchsorted(times, ref_times - 1e-12)
    deviation = np.abs(alpha[at] - ref).max() / np.abs(ref - ref[0]).max()
    assert deviation < 1e-5, deviation


def test_radau_converges_at_order_three_or_more_and_reaches_1e_4_at_10_ms(rod):
    _, tips = rod
    coarse, half = _error(tips, 1e-2), _error(tips, 5e-3)
    assert coarse < 1e-4, coarse
    assert half < coarse / 8, (coarse, half)
