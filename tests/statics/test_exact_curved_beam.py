"""The `exact` model of a curved beam: the same arc as a geometrically exact elastica, on
the seed-000 gripper, against the linear and partial non-linear models."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import ACTUATION, EXAMPLES

from flexmech import models
from flexmech.service.solvers.equilibrium import solve_equilibrium
from flexmech.service.solvers.stiffness import tangent_stiffness
from flexmech.service.solvers.sweep import solve_for_target


@pytest.fixture(scope="module")
def gripper_models():
    document = models.load_document(json.loads((EXAMPLES / "gripper.json").read_text()))
    return {model: models.compile_mechanism(document, model=model) for model in ("partial_nonlinear", "exact")}


def motion(mech, force: float) -> np.ndarray:
    result = solve_equilibrium(mech.with_values({ACTUATION: force}))
    assert result.converged, result.message
    out = result.outputs()
    return np.array(
        [out["end_effector.dx"], out["end_effector.dy"], out["bodies.input.y"] - mech.value("/bodies/input/position/1")]
    )


def test_exact_and_partial_nonlinear_share_the_undeformed_tangent_stiffness(gripper_models):
    """At zero load the exact arc has the compliance of Eq. 2, so K_T (the links' unknowns
    condensed out) equals the partial non-linear model's, to the discretization error of the
    default 8 intervals (about 5e-9 here; 16 intervals take it 2^8 times lower)."""
    pnl = tangent_stiffness(gripper_models["partial_nonlinear"]).K
    # Entries mix units (force/length, moment/angle, ...): compare each with its row and column.
    scale = np.sqrt(np.abs(pnl).max(axis=1, keepdims=True) * np.abs(pnl).max(axis=0, keepdims=True))
    exact = tangent_stiffness(gripper_models["exact"]).K
    assert (np.abs(exact - pnl) / scale).max() < 2e-8
    fine = json.loads((EXAMPLES / "gripper.json").read_text())
    for element in fine["elements"].values():
        element.update(model="exact", intervals=16)
    exact_fine = tangent_stiffness(models.compile_mechanism(models.load_document(fine))).K
    assert (np.abs(exact_fine - pnl) / scale).max() < 1e-10


def test_exact_agrees_with_partial_nonlinear_at_small_loads(gripper_models):
    """The models differ by a term of first order in the load: the relative difference of
    the end-effector and input motions falls tenfold from 1 uN to 0.1 uN, and is below
    1e-3 at 0.1 uN (at 1 uN it is 1.5e-3 to 2.7e-3: pnl's first-order error, not a limit
    of the exact model)."""
    differences = {}
    for force in (1.0, 0.1):
        exact, pnl = motion(gripper_models["exact"], force), motion(gripper_models["partial_nonlinear"], force)
        differences[force] = np.abs(pnl - exact) / np.abs(exact)
    assert differences[0.1].max() < 1e-3
    assert differences[1.0] / differences[0.1] == pytest.approx(np.full(3, 10.0), rel=0.05)


def test_exact_closing_force_scales_with_E_silicon_to_nylon(gripper_models):
    """An inextensible elastica under given forces deforms alike when EI scales, so the
    closing force of nylon is silicon's times E_nylon / E_silicon (1 / 26.0417)."""
    silicon = solve_for_target(gripper_models["exact"], ACTUATION, "end_effector.x", 0.0)
    nylon_document = models.load_document(json.loads((EXAMPLES / "gripper_nylon.json").read_text()))
    nylon = solve_for_target(models.compile_mechanism(nylon_document, model="exact"), ACTUATION, "end_effector.x", 0.0)
    assert silicon.status == nylon.status == "converged"
    ratio = nylon_document.materials["nylon"].E / 100.0  # GPa, silicon is 100 GPa in gripper.json
    assert nylon.value == pytest.approx(silicon.value * ratio, rel=1e-8)
    # Between the linear model (63.95 uN) and the partial non-linear one (77.03 uN).
    assert 63.95 < silicon.value < 77.03
