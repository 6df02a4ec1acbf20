"""Arc-length continuation through the snap-through of a shallow clamped arch."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import EXAMPLES
from continuation_oracles import natural_limit

from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service.solvers.continuation import _path_graphs, body_stability, trace_path

LOAD = "/loads/P/force/1"


@pytest.fixture(scope="module")
def arch():
    return compile_mechanism(load_document(EXAMPLES / "snap_through_arch.json"))


@pytest.fixture(scope="module")
def path(arch):
    return trace_path(arch, LOAD, -300.0, 20.0)


def test_the_path_passes_both_limit_points_and_reaches_the_stop(path):
    assert path.status == "completed"
    assert path.points[-1].value == pytest.approx(-300.0, rel=1e-12)
    assert [lp.kind for lp in path.limit_points] == ["minimum", "maximum"]
    first, second = path.limit_points
    assert first.value < second.value < 0  # the load drops after the first: snap-through
    dy = [p.outputs["crown.dy"] for p in path.points]
    assert np.all(np.diff(dy) < 0)  # the crown moves down all along the path
    assert first.residual < 1e-10 and second.residual < 1e-10


def test_limit_loads_equal_bisection_on_natural_continuation(arch, path):
    first, second = path.limit_points
    loading = natural_limit(arch, LOAD, 0.0, -10.0, rel_tol=1e-9)
    assert loading == pytest.approx(first.value, rel=1e-6)
    # Unloading from the snapped-through state: the branch ends at the second limit point.
    unloading = natural_limit(arch, LOAD, -300.0, 10.0, z0=path.points[-1].z, rel_tol=1e-9)
    assert unloading == pytest.approx(second.value, rel=1e-6)


def test_stability_changes_exactly_at_the_limit_points(arch, path):
    changes = [
        i for i in range(len(path.points) - 1) if path.points[i].stability.stable != path.points[i + 1].stability.stable
    ]
    assert changes == [lp.after_point for lp in path.limit_points]
    assert all(p.stability.symmetric for p in path.points)
    slot = arch.parameter_index(LOAD)
    path_fn, _ = _path_graphs(arch.structure, slot)
    p = arch.p()
    for lp in path.limit_points:
        K = np.asarray(path_fn(lp.z, lp.value * arch.nd_per_doc("force"), p)[1])
        assert np.linalg.svd(K, compute_uv=False)[-1] < 1e-9 * np.linalg.norm(K)
        # Just before and after: the body stiffness' least eigenvalue changes sign.
        before, after = path.points[lp.after_point], path.points[lp.after_point + 1]
        assert before.stability.eigenvalues[0] * after.stability.eigenvalues[0] < 0


def test_stability_of_the_unloaded_arch_is_its_positive_definite_stiffness(arch):
    K = np.asarray(arch.graphs.residual_and_tangent(np.zeros(arch.n_free), arch.p())[1])
    stability = body_stability(arch, K)
    assert stability.stable and stability.symmetric and min(stability.eigenvalues) > 0


def test_bad_continuation_input(arch):
    with pytest.raises(MechanismError) as info:
        trace_path(arch, LOAD, -300.0, 0.0)
    assert info.value.pointer == "/step" and "must be positive" in info.value.problem
    with pytest.raises(MechanismError) as info:
        trace_path(arch, "/loads/P/force/7", -300.0, 1.0)
    assert "not a numeric field" in info.value.problem
