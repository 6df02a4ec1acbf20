"""The gripper of seed 000 against the paper's tables and the reading notes."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import ACTUATION, EXAMPLES

from flexmech.models import compile_mechanism, load_document
from flexmech.service import NewtonOptions, inverse_wrenches, solve_equilibrium, solve_for_target, tangent_stiffness
from flexmech.service.solvers.inverse import configuration_of

# Table 2: K_T of the partial non-linear model, undeformed (uN/mm, uN, uN mm/rad); 0 = not coupled.
TABLE_2 = np.array(
    [
        [2.40e3, 1.84e2, -5.42e2, -1.32e3, -1.11e2, -1.01e3, 0, 0, 0],
        [1.84e2, 2.71e3, -1.34e3, -1.11e2, -1.09e3, -1.46e2, 0, 0, 0],
        [-5.42e2, -1.34e3, 2.29e3, 6.76e2, -3.29e2, 4.70e2, 0, 0, 0],
        [-1.32e3, -1.11e2, 6.76e2, 2.41e3, 2.06e2, 4.98e2, -1.10e3, -9.53e1, 4.31e2],
        [-1.11e2, -1.09e3, -3.29e2, 2.06e2, 2.30e3, -6.44e2, -9.53e1, -1.21e3, -1.75e2],
        [-1.01e3, -1.46e2, 4.70e2, 4.98e2, -6.44e2, 1.51e3, 5.07e2, 7.89e2, -9.01e1],
        [0, 0, 0, -1.10e3, -9.53e1, 5.07e2, 2.34e3, -5.58e1, -3.75e2],
        [0, 0, 0, -9.53e1, -1.21e3, 7.89e2, -5.58e1, 4.16e3, -1.08e3],
        [0, 0, 0, 4.31e2, -1.75e2, -9.01e1, -3.75e2, -1.08e3, 7.93e2],
    ]
)
PER_RAD = np.array([1, 1, np.pi / 180] * 3)  # document angles are degrees


def stiffness_per_rad(mech, z=None):
    ts = tangent_stiffness(mech, z)
    return ts.K / PER_RAD[None, :], {k: v / PER_RAD[None, :] for k, v in ts.terms.items()}


def test_table_2_all_63_entries_within_half_a_percent(gripper_pnl):
    K, _ = stiffness_per_rad(gripper_pnl)
    coupled = TABLE_2 != 0
    assert coupled.sum() == 63
    rel = np.abs(K[coupled] - TABLE_2[coupled]) / np.abs(TABLE_2[coupled])
    assert rel.max() < 5e-3, f"worst entry off by {rel.max():.3%}"
    assert np.all(K[~coupled] == 0.0)  # body 2 and body 4 share no flexure


def test_undeformed_tangent_is_symmetric_and_models_agree(gripper):
    K, _ = stiffness_per_rad(gripper)
    np.testing.assert_allclose(K, K.T, atol=1e-9 * np.abs(K).max())
    pnl = compile_mechanism(load_document(EXAMPLES / "gripper.json"), model="partial_nonlinear")
    np.testing.assert_allclose(K, stiffness_per_rad(pnl)[0], rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("model, expected", [("linear", 63.95), ("partial_nonlinear", 77.04)])
def test_closing_force(model, expected):
    mech = compile_mechanism(load_document(EXAMPLES / "gripper.json"), model=model)
    target = solve_for_target(mech, ACTUATION, "end_effector.x", 0.0)
    assert target.status == "converged"
    assert target.value == pytest.approx(expected, abs=0.05)
    # the state found really is an equilibrium with the gripper closed
    check = solve_equilibrium(mech.with_values({ACTUATION: target.value}))
    assert abs(check.outputs()["end_effector.x"]) < 1e-9


def test_table_6_geometric_term_at_50_uN(gripper_pnl):
    mech = gripper_pnl.with_values({ACTUATION: 50.0})
    eq = solve_equilibrium(mech)
    _, terms = stiffness_per_rad(mech, eq.z)
    K2 = terms["II"]
    assert K2[0, 2] == pytest.approx(-50.0, rel=1e-9)  # z_2 of Eq. 48: -F_2y
    others = K2.copy()
    others[0, 2] = 0.0
    assert np.abs(others).max() < 1e-8  # Table 6's other entries are round-off (1e-11)


@pytest.mark.parametrize("force", [50.0, -40.0])
def test_tangent_equals_central_differences_at_a_deformed_state(gripper, force):
    mech = gripper.with_values({ACTUATION: force})
    eq = solve_equilibrium(mech)
    p = mech.p()
    _, K = mech.graphs.residual_and_tangent(eq.z, p)
    K = np.asarray(K)
    h = 1e-6
    K_fd = np.zeros_like(K)
    for j in range(mech.n_free):
        e = np.zeros(mech.n_free)
        e[j] = h
        up = np.asarray(mech.graphs.residual(eq.z + e, p)).ravel()
        down = np.asarray(mech.graphs.residual(eq.z - e, p)).ravel()
        K_fd[:, j] = (up - down) / (2 * h)
    np.testing.assert_allclose(K, K_fd, rtol=1e-6, atol=1e-6 * np.abs(K).max())


def test_tangent_terms_sum_to_tangent(gripper):
    mech = gripper.with_values({ACTUATION: 60.0})
    eq = solve_equilibrium(mech)
    ts = tangent_stiffness(mech, eq.z)
    total = sum(ts.terms.values())
    np.testing.assert_allclose(total, ts.K, rtol=1e-12, atol=1e-12 * np.abs(ts.K).max())
    if mech.structure.of_family("curved_beam")[0].model == "linear":
        assert np.abs(ts.terms["III"]).max() == 0.0  # Eq. 28: no third term
    else:
        assert np.abs(ts.terms["III"]).max() > 0.0
    assert not ts.symmetric  # Table 3: not symmetric once deformed
    assert tangent_stiffness(mech).symmetric  # Table 2: symmetric undeformed (angles in degrees here)


def test_inverse_round_trips_a_forward_solve(gripper):
    forces = {ACTUATION: 42.0, "/loads/actuation/force/0": -7.5}
    mech = gripper.with_values(forces)
    eq = solve_equilibrium(mech)
    held = inverse_wrenches(mech, configuration_of(mech, eq.z))
    np.testing.assert_allclose(held["input"], [-7.5, 42.0, 0.0], rtol=0, atol=1e-9 * 42.0)
    for body in ("coupler", "follower"):
        np.testing.assert_allclose(held[body], 0.0, atol=1e-9 * 42.0)
    # the frame's wrench is the flexures' pull on it: equal to the support reaction reported
    out = eq.outputs()
    np.testing.assert_allclose(held["frame"], [out["anchor.Fx"], out["anchor.Fy"], out["anchor.M"]], rtol=1e-12)


def test_nylon_forces_are_silicon_forces_over_26_0417():
    for model in ("linear", "partial_nonlinear"):
        si = compile_mechanism(load_document(EXAMPLES / "gripper.json"), model=model)
        ny = compile_mechanism(load_document(EXAMPLES / "gripper_nylon.json"), model=model)
        f_si = solve_for_target(si, ACTUATION, "end_effector.x", 0.0).value
        f_ny = solve_for_target(ny, ACTUATION, "end_effector.x", 0.0).value
        assert f_si / f_ny == pytest.approx(100 / 3.84, rel=1e-9)
        assert f_si / f_ny == pytest.approx(26.0417, abs=5e-5)


def test_frozen_tangent_converges_at_70_and_not_at_78(gripper_pnl):
    """Fig. 11: Newton with K_T frozen at the undeformed state (the paper's plain iteration)."""
    frozen = NewtonOptions(jacobian="frozen", line_search=False, max_iterations=1000)
    at_70 = solve_equilibrium(gripper_pnl.with_values({ACTUATION: 70.0}), frozen)
    at_78 = solve_equilibrium(gripper_pnl.with_values({ACTUATION: 78.0}), frozen)
    assert at_70.status == "converged"
    assert at_70.iterations > 50  # slow linear convergence near the limit
    assert at_78.status == "not_converged"
    full = solve_equilibrium(gripper_pnl.with_values({ACTUATION: 78.0}))
    assert full.status == "converged" and full.iterations <= 8


def test_first_term_strategy_converges_to_the_same_state(gripper_pnl):
    mech = gripper_pnl.with_values({ACTUATION: 60.0})
    full = solve_equilibrium(mech)
    first = solve_equilibrium(mech, NewtonOptions(jacobian="first_term", max_iterations=100))
    assert first.status == "converged"
    assert first.iterations > full.iterations  # Fig. 12: K_T^I alone needs more iterations
    np.testing.assert_allclose(first.z, full.z, atol=1e-9)


def test_si_copy_gives_the_same_physics():
    mm = compile_mechanism(load_document(EXAMPLES / "gripper.json"))
    si = compile_mechanism(load_document(EXAMPLES / "gripper_si.json"))
    f_mm = solve_for_target(mm, ACTUATION, "end_effector.x", 0.0).value  # uN
    f_si = solve_for_target(si, ACTUATION, "end_effector.x", 0.0).value  # N
    assert f_si == pytest.approx(f_mm * 1e-6, rel=1e-9)
    # the solver sees the same nondimensional problem
    np.testing.assert_allclose(si.p(), mm.p(), rtol=1e-12, atol=1e-15)
    out_mm = solve_equilibrium(mm).outputs()
    out_si = solve_equilibrium(si).outputs()
    assert out_si["end_effector.x"] == pytest.approx(out_mm["end_effector.x"] * 1e-3, rel=1e-9)
    assert out_si["elements.a.stress_max"] == pytest.approx(out_mm["elements.a.stress_max"] * 1e9, rel=1e-9)


@pytest.mark.parametrize("restart", ["previous", "undeformed"])
def test_opening_closing_movement(gripper, restart):
    """Fig. 7/9: from -60 uN (open) until the end effector reaches x = 0 (closed)."""
    from flexmech.service.solvers.sweep import document_sweep

    result, closing = document_sweep(gripper, start=restart)
    assert result.all_converged and len(result.values) == 101
    assert result.values[0] == -60.0 and result.values[-1] == pytest.approx(closing.value, rel=1e-12)
    x = result.outputs["end_effector.x"]
    assert abs(x[-1]) < 1e-9
    closing_half = result.values >= 0
    assert np.all(np.diff(x[closing_half]) < 0)  # pushing up closes the gripper steadily
    undeformed_x = 1.8 - 1.3571
    assert x[0] > undeformed_x > x[-1]
    if restart == "previous":  # Fig. 12: continuation needs fewer iterations than restarting
        cold, _ = document_sweep(gripper, start="undeformed")
        assert result.iterations.sum() < cold.iterations.sum()
