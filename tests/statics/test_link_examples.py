"""The seed-002 example documents (examples/*.json) against what is known of them."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import EXAMPLES
from elastica_oracles import cantilever_tip

from flexmech import models
from flexmech.service.solvers.equilibrium import NewtonOptions, solve_equilibrium
from flexmech.service.solvers.inverse_links import inverse_links
from flexmech.service.solvers.sweep import document_sweep

LINK_EXAMPLES = [
    "cantilever",
    "compliant_slider",
    "parallel_mechanism",
    "planar_spring",
    "curved_indexer",
    "six_bar",
    "inverse_four_bar",
    "gripper_exact",
]
TIGHT = NewtonOptions(tol_residual=1e-13, tol_step=1e-12)


def example(name: str) -> models.Mechanism:
    return models.compile_mechanism(models.load_document(json.loads((EXAMPLES / f"{name}.json").read_text())))


@pytest.mark.parametrize("name", LINK_EXAMPLES)
def test_every_link_example_solves_under_its_loads(name):
    mech = example(name)
    result = solve_equilibrium(mech)
    assert result.converged, result.message
    errors = [v for k, v in result.outputs().items() if k.endswith(".discretization_error")]
    assert errors and max(errors) < 1e-6  # each example runs at a resolution that is accurate


def test_cantilever_example_in_mm_is_the_elastica():
    out = solve_equilibrium(example("cantilever"), TIGHT).outputs()
    x, y, rotation = cantilever_tip(0.08, 0.1016, 15.0)
    assert out["tip.x"] == pytest.approx(x * 1e3, rel=1e-9)  # the document is in mm
    assert out["tip.y"] == pytest.approx(y * 1e3, rel=1e-9)
    assert out["bodies.tip.angle"] == pytest.approx(math.degrees(rotation), rel=1e-9)


def test_planar_spring_stiffness_and_its_stiffening():
    """Published: 3.2667e4 N/m for one spring, 'linear'; it stiffens by about 5 % at 2 um."""
    mech = example("planar_spring")
    sweep, _ = document_sweep(mech, TIGHT)
    assert all(s == "converged" for s in sweep.status)
    dX = np.asarray(sweep.values) * 1e-6  # m
    force = np.asarray(sweep.outputs["spring_force.Fx"]) * 1e-3  # N
    small = solve_equilibrium(mech.with_values({"/loads/dX/dx": 1e-3}), TIGHT).outputs()
    stiffness = small["spring_force.Fx"] * 1e-3 / 1e-9
    assert stiffness == pytest.approx(3.2667e4, rel=1e-2)
    assert dX[-1] == pytest.approx(2e-6)
    secant = force[-1] / dX[-1]
    assert 1.04 < secant / stiffness < 1.06
    assert np.all(np.diff(force[1:] / dX[1:]) > 0)  # stiffening all the way
    # The point-symmetric shape carries no transverse force.
    assert np.abs(sweep.outputs["spring_force.Fy"]).max() < 1e-6 * np.abs(force).max() * 1e3


def test_parallel_mechanism_small_push_is_two_guided_beams():
    """Each link is clamped to ground and to the rigid coupler, which only translates at
    first order: P = 2 x 12 EI / L^3 per unit push."""
    mech = example("parallel_mechanism").with_values({"/loads/push/dx": 1e-4})
    out = solve_equilibrium(mech, TIGHT).outputs()
    EI, L = 0.3, 0.0254
    assert out["P.Fx"] / 1e-7 == pytest.approx(24 * EI / L**3, rel=1e-5)


def test_inverse_four_bar_gives_the_branch_through_the_unloaded_state():
    mech = example("inverse_four_bar")
    spec = mech.document.inverse
    result = inverse_links(mech, spec.shapes, spec.internal_forces, spec.unknown_loads)
    assert result.converged, result.message
    force = result.loads["/loads/F/force/0"]
    # Force balance at J2 (Eq. 5.2a): h1 - h2 = Fx, and at J3 h2 = h3 (given).
    assert result.links["L2"]["h"] == pytest.approx(-5.0, rel=1e-10)
    assert result.links["L1"]["h"] - result.links["L2"]["h"] == pytest.approx(force, rel=1e-10)
    # The clamped fixed ends keep their angles: eta = psi there (Eq. 5.3d).
    psi1, psi3 = spec.shapes["L1"]["polynomial"], spec.shapes["L3"]["polynomial"]
    assert result.links["L1"]["eta"][0] == pytest.approx(psi1[0], abs=1e-10)
    assert result.links["L3"]["eta"][-1] == pytest.approx(sum(psi3), abs=1e-10)
    assert 30.0 < force < 40.0  # 35.9 N; the thesis prints 32.48 N (see the README)
