"""Seed 004's CSFH at rest: damped, the impact simulation settles where the contact analysis
(energy minimization with the pin inside the hole, IPOPT) puts it: the body resting on the
conjugate surface, the flexure sagged beyond the clearance."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from impact_cases import csfh, parsed

from flexmech.models.documents.simulation_spec import SimulateSpec
from flexmech.service.analysis import run_analysis
from flexmech.service.impacts.run import run_impacts
from flexmech.service.requests import compile_request
from flexmech.service.solvers.newton import NewtonOptions


def _resting_document() -> dict:
    doc = copy.deepcopy(csfh("6.3"))
    doc["elements"]["flexure"]["model"] = "conservative"  # the energy of the impact models' constant stiffness
    pair = doc["contacts"]["pairs"]["conjugate"]
    pair["normal"] = {"law": "hertz", "stiffness": 1e13, "exponent": 1.5}  # stiff: 4e-8 m of indentation at rest
    pair["friction"] = {"law": "none"}
    doc["simulate"].update(
        until=2.5, damping=30.0, tolerance=1e-9, initial={"hinge": {"displacement": [0.0, 0.0, 0.0]}}
    )
    return doc


def test_the_damped_csfh_settles_to_the_contact_analysis_equilibrium():
    doc = _resting_document()
    exact = copy.deepcopy(doc)  # the same pair, with the law a quasi-static solve takes
    exact["contacts"]["pairs"]["conjugate"]["normal"] = {"law": "unilateral"}
    static = run_analysis(compile_request(exact), "contact", NewtonOptions())
    assert static["status"] == "converged"
    x, y = static["outputs"]["bodies.hinge.x"], static["outputs"]["bodies.hinge.y"]
    theta = np.radians(static["outputs"]["bodies.hinge.angle"])
    assert np.hypot(x, y) == pytest.approx(0.02, abs=1e-9)  # on the conjugate surface
    document, spec = parsed(doc)
    report = run_impacts(document, SimulateSpec.model_validate(doc["simulate"]))[1]
    assert report["status"] == "finished"
    end = {k: v[-1] for k, v in report["coordinates"].items()}
    assert end["hinge.x"] == pytest.approx(x, abs=1e-6)
    assert end["hinge.y"] == pytest.approx(y, abs=1e-6)
    assert np.radians(end["hinge.theta"]) == pytest.approx(theta, abs=1e-6)
    # the stiff contact rings at the integrator's tolerance (1e-10 m), which is a newton in force
    normal = report["contacts"]["conjugate"]["normal_force"][-1]
    assert normal == pytest.approx(static["pairs"]["conjugate"]["normal_force"], rel=2e-2)
    assert max(abs(v[-1]) for v in report["velocities"].values()) < 1e-4
