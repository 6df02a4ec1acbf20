"""The pin and slider families with springs: Howell's 1R pseudo-rigid-body model of the thesis
cantilever against its closed form and beside the elastica, a slider's travel and reactions,
and a closed loop of rigid bodies whose ground balances the loads."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import EXAMPLES
from mechanisms import four_bar

from flexmech.models import compile_mechanism, load_document
from flexmech.service.solvers.equilibrium import NewtonOptions, solve_equilibrium

TIGHT = NewtonOptions(tol_residual=1e-13, tol_step=1e-12)
GAMMA, K_THETA, EI, L = 0.85, 2.65, 0.08, 0.1016  # Howell's 1R constants; the thesis cantilever


def prbm_tip_force(theta: float) -> float:
    """F L^2 cos(Theta) = K_Theta EI Theta: the 1R model's tip force for the angle Theta."""
    return K_THETA * EI * theta / (L**2 * math.cos(theta))


def test_the_1r_model_equals_its_closed_form_and_stays_near_the_elastica(capsys):
    mech = compile_mechanism(load_document(EXAMPLES / "prbm_cantilever.json"))
    rows, guess = [], None
    for degrees in (10, 20, 30, 40, 50, 60):
        theta = math.radians(degrees)
        F = prbm_tip_force(theta)
        loaded = mech.with_values({"/loads/F_prb/force/1": F, "/loads/F_elastica/force/1": F})
        result = solve_equilibrium(loaded, TIGHT, guess=guess)
        assert result.converged
        guess = result.z
        out = result.outputs()
        x = L * (1 - GAMMA) + GAMMA * L * math.cos(theta)
        y = GAMMA * L * math.sin(theta)
        assert math.radians(out["bodies.prb.angle"]) == pytest.approx(theta, rel=1e-9)
        assert out["prb_tip.x"] / 1e3 == pytest.approx(x, abs=1e-9 * L)
        assert out["prb_tip.y"] / 1e3 == pytest.approx(y, abs=1e-9 * L)
        assert out["elements.hinge.M"] / 1e3 == pytest.approx(F * GAMMA * L * math.cos(theta), rel=1e-9)
        gap = math.hypot(out["elastica_tip.x"] / 1e3 - x, out["elastica_tip.y"] / 1e3 - y) / L
        assert gap < 0.015
        rows.append((degrees, F, out["elastica_tip.x"], out["elastica_tip.y"], x * 1e3, y * 1e3, 100 * gap))
    with capsys.disabled():
        print("\nTheta [deg]  F [N]     elastica tip [mm]      1R tip [mm]            gap [% of L]")
        for row in rows:
            print("{:5d}      {:7.3f}   ({:8.4f}, {:8.4f})   ({:8.4f}, {:8.4f})   {:.3f}".format(*row))


def test_a_slider_carries_the_normal_force_and_the_spring_the_axial_one():
    angle = math.radians(30)
    axis, normal = np.array([math.cos(angle), math.sin(angle)]), np.array([-math.sin(angle), math.cos(angle)])
    force = np.array([3.0, -2.0])
    k = 50.0
    document = {
        "units": {"length": "m", "force": "N", "angle": "rad"},
        "bodies": {"ground": {"fixed": True, "position": [0, 0]}, "block": {"position": [axis[0], axis[1]]}},
        "elements": {
            "guide": {"type": "slider", "from": "ground", "to": "block", "angle": angle},
            "spring": {"type": "spring", "from": "ground", "to": "block", "stiffness": k},
        },
        "loads": {"push": {"type": "force", "body": "block", "force": force.tolist()}},
    }
    result = solve_equilibrium(compile_mechanism(load_document(document)), TIGHT)
    out = result.outputs()
    travel = force @ axis / k
    assert out["elements.guide.travel"] == pytest.approx(travel, rel=1e-12)
    assert out["elements.spring.extension"] == pytest.approx(travel, rel=1e-12)
    assert out["elements.spring.F"] == pytest.approx(force @ axis, rel=1e-12)
    assert out["elements.guide.N"] == pytest.approx(-force @ normal, rel=1e-12)  # the guide holds the rest
    assert out["elements.guide.M"] == pytest.approx(0.0, abs=1e-12)
    assert out["bodies.block.angle"] == pytest.approx(0.0, abs=1e-12)


def test_pins_and_springs_close_a_loop_and_the_ground_balances_the_loads():
    """A four-bar of rigid bodies on pins with springs: whatever the pin forces, the ground's
    reaction balances the applied force and moment (about the ground's reference point)."""
    mech = compile_mechanism(load_document(four_bar()))
    result = solve_equilibrium(mech, TIGHT)
    assert result.converged and result.iterations > 2  # the springs' laws are nonlinear
    out = result.outputs()
    Fx, Fy, M = 1.5, -2.0, 0.4
    assert out["ground.Fx"] == pytest.approx(-Fx, abs=1e-12)
    assert out["ground.Fy"] == pytest.approx(-Fy, abs=1e-12)
    assert out["ground.M"] == pytest.approx(-(out["P.x"] * Fy - out["P.y"] * Fx + M), abs=1e-12)
    # Each pin passes equal and opposite forces: the coupler's pins balance its load.
    assert out["elements.B.Fx"] - out["elements.C.Fx"] + Fx + out["elements.pull.F"] * _pull_direction(out)[
        0
    ] == pytest.approx(0.0, abs=1e-12)


def _pull_direction(out: dict) -> np.ndarray:
    """The unit vector from the coupler's spring point towards the ground's (the tension's
    direction on the coupler)."""
    d = np.array([0.6 - out["Q.x"], -0.4 - out["Q.y"]])
    return d / np.linalg.norm(d)
