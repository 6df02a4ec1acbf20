"""The compiled fast path against the interpreted graphs and the Python Newton."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from conftest import ACTUATION

from benchmarks.numpy_peer import NumpyGripperResidual
from flexmech.models import MechanismError
from flexmech.service import NewtonOptions, solve_equilibrium, sweep
from flexmech.service.solvers.fastpath import FastPath


@pytest.fixture()
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("FLEXMECH_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path / "cache"


def test_compiled_solve_equals_python_newton(gripper, private_cache):
    mech = gripper.with_values({ACTUATION: 65.0})
    fast = FastPath(mech)
    assert fast.compiled
    assert len(list(private_cache.glob("libraries/fast_solve_*.so"))) == 1
    z, norm = fast.solve()
    assert norm < 1e-10
    np.testing.assert_allclose(z, solve_equilibrium(mech).z, atol=1e-12)


def test_library_is_reused_from_the_disk_cache(gripper_pnl, private_cache):
    FastPath(gripper_pnl)
    (library,) = private_cache.glob("libraries/fast_solve_*.so")
    stamp = library.stat().st_mtime_ns
    other_numbers = gripper_pnl.with_values({"/sections/flexure/h": "6 um", ACTUATION: 10.0})
    again = FastPath(other_numbers)  # same structure: no new compilation
    assert library.stat().st_mtime_ns == stamp
    assert len(list(private_cache.glob("libraries/fast_solve_*.so"))) == 1
    np.testing.assert_allclose(again.solve()[0], solve_equilibrium(other_numbers).z, atol=1e-12)


def test_without_a_compiler_the_virtual_machine_gives_the_same_answer(gripper_pnl, private_cache, monkeypatch):
    monkeypatch.setenv("FLEXMECH_CC", "/nonexistent/cc")
    monkeypatch.setenv("PATH", "/nonexistent")
    slow = FastPath(gripper_pnl)
    assert not slow.compiled
    assert not private_cache.exists()
    np.testing.assert_allclose(slow.solve()[0], solve_equilibrium(gripper_pnl).z, atol=1e-12)


def test_compiled_sweep_equals_python_continuation(gripper, private_cache):
    values = np.linspace(-60.0, 70.0, 27)
    fast = FastPath(gripper)
    Z, norms, Y = fast.sweep(fast.path_parameters(ACTUATION, values))
    assert norms.max() < 1e-10
    reference = sweep(gripper, ACTUATION, values, NewtonOptions())
    assert reference.all_converged
    np.testing.assert_allclose(Z.T, reference.z, atol=1e-10)  # both stop at |R| <= 1e-10 or better
    i = gripper.graphs.output_names.index("end_effector.x")
    np.testing.assert_allclose(Y[i] / gripper.nd_per_doc("length"), reference.outputs["end_effector.x"], atol=1e-10)
    # a sweep that computes only the outputs asked for gives the same numbers
    trajectory = FastPath(gripper, outputs=("end_effector.y", "end_effector.x"))
    _, _, Y2 = trajectory.sweep(trajectory.path_parameters(ACTUATION, values))
    np.testing.assert_allclose(Y2[1], Y[i], atol=1e-14)
    with pytest.raises(MechanismError, match="unknown output"):
        FastPath(gripper, outputs=("end_effector.z",))


def test_fast_path_reports_failure_through_the_residual(gripper_pnl, private_cache):
    fast = FastPath(gripper_pnl.with_values({ACTUATION: 1e4}))
    _, norm = fast.solve()
    assert norm > 1e-3  # no line search: the caller sees the residual and falls back


def test_residual_matches_an_independent_numpy_implementation(gripper):
    """The numpy peer of the benchmark is written from the paper's equations separately."""
    peer = NumpyGripperResidual(gripper.with_values({ACTUATION: 33.0}))
    mech = gripper.with_values({ACTUATION: 33.0})
    rng = np.random.default_rng(7)
    for _ in range(5):
        z = rng.normal(scale=0.3, size=mech.n_free)
        np.testing.assert_allclose(
            np.asarray(mech.graphs.residual(z, mech.p())).ravel(), peer(z), rtol=1e-12, atol=1e-13
        )


def test_graphs_are_closed_serializable_and_map_like_a_loop(gripper_pnl):
    g = gripper_pnl.graphs
    for fn in (g.residual, g.residual_and_tangent, g.tangent_terms, g.outputs, g.body_wrenches):
        assert not fn.has_free()
    copy = ca.Function.deserialize(g.residual.serialize())
    p = gripper_pnl.p()
    Zs = np.random.default_rng(1).normal(scale=0.2, size=(gripper_pnl.n_free, 6))
    mapped = np.asarray(g.residual.map(6)(Zs, p))
    for k in range(6):
        np.testing.assert_allclose(np.asarray(copy(Zs[:, k], p)).ravel(), mapped[:, k], rtol=1e-14, atol=1e-15)
