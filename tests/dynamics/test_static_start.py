"""A simulation's static start by Newton on the element kernels (service.dynamics.static_start)
against the minimum of the dense energy form found by IPOPT (service.solvers.energy), an independent
solver on another assembly of the same physics; the path in fractions of the loads, the
fallback to IPOPT, and a 128-element rod against an 8-element one."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import EXAMPLES

from flexmech.models import compile_mechanism, load_document
from flexmech.service.dynamics import static_start
from flexmech.service.dynamics.histories import read_histories
from flexmech.service.dynamics.run import scheme_of, simulation_spec, start_shape
from flexmech.service.dynamics.stepping import engine_of
from flexmech.service.solvers.energy import minimize_energy


def _mechanism(example: str, change=None):
    doc = json.loads((EXAMPLES / example).read_text())
    doc.setdefault("simulate", {})["start"] = "equilibrium"
    if change is not None:
        change(doc)
    return compile_mechanism(load_document(doc))


def _engine(mech):
    spec = simulation_spec(mech, {"until": 0.01})
    return engine_of(mech.structure, scheme_of(spec), read_histories(mech, spec.histories, spec.until))


def _twice_the_hold(doc):
    doc["loads"]["hold"]["force"] = [2 * f for f in doc["loads"]["hold"]["force"]]


@pytest.mark.parametrize(
    "example, change",
    [
        ("rod_free_vibration.json", None),
        ("rod_free_vibration.json", _twice_the_hold),
        ("rod_tip_mass_gravity.json", None),
    ],
    ids=["rod", "rod, twice the hold", "tip mass"],
)
def test_the_kernel_start_is_the_minimum_of_the_energy(example, change):
    mech = _mechanism(example, change)
    kernel = static_start.static_shape(_engine(mech), mech.p())
    ipopt = mech.graphs.energy_form.x_of_state(minimize_energy(mech).z)
    assert kernel is not None
    assert np.abs(ipopt).max() > 1e-3  # a start that is not the undeformed state
    np.testing.assert_allclose(kernel, ipopt, rtol=0, atol=1e-9 * np.abs(ipopt).max())


def test_the_loads_applied_in_fractions_reach_the_same_equilibrium():
    mech = _mechanism("rod_free_vibration.json")
    engine = _engine(mech)
    loads = np.array([q.pointer.startswith(static_start.LOADING) for q in mech.parameters])
    assert loads.sum() == 2  # the hold force's two components
    at_once = static_start._along_the_path(engine, mech.p(), loads, 1)
    in_fourths = static_start._along_the_path(engine, mech.p(), loads, 4)
    np.testing.assert_allclose(in_fourths, at_once, rtol=0, atol=1e-11)


def test_a_start_the_kernels_do_not_settle_falls_back_to_the_energy_minimum(monkeypatch):
    mech = _mechanism("rod_tip_mass_gravity.json")
    spec = simulation_spec(mech, {"until": 0.01})
    kernel, _ = start_shape(mech, spec)
    monkeypatch.setattr(static_start, "MAX_ITERATIONS", 1)  # Newton cannot settle in one iteration
    assert static_start.static_shape(_engine(mech), mech.p()) is None
    fallback, note = start_shape(mech, spec)
    assert note == "from rest, in static equilibrium under the document's values"
    np.testing.assert_allclose(fallback, kernel, rtol=0, atol=1e-9 * np.abs(kernel).max())


def test_a_rod_of_128_elements_starts_where_one_of_8_does():
    """Cubic elements: 8 already place the held tip to about 1e-10 (of the rod's length); 128
    (the most a link takes) must agree, and its start is built without the dense form."""
    tips = []
    for n in (8, 128):
        mech = _mechanism("rod_free_vibration.json", lambda d, n=n: d["elements"]["rod"].update(intervals=n))
        engine = _engine(mech)
        x = static_start.static_shape(engine, mech.p())
        tips.append(x[list(engine.system.layout.x_global)])
        assert "graphs" not in mech.__dict__  # the dense statics graph was never built
    assert np.abs(tips[0]).max() > 0.3
    np.testing.assert_allclose(tips[1], tips[0], rtol=0, atol=1e-8)
