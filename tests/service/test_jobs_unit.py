"""The sweep job kind and the job store, without a server: grids, load paths, resumption,
validation messages, and that workers reuse what they built."""

from __future__ import annotations

import json

import pytest
from conftest import ACTUATION, EXAMPLES

from flexmech.models import MechanismError
from flexmech.models.graph.assembly import graphs_for
from flexmech.service.analysis import Limits
from flexmech.service.jobs import sweep as sweep_kind
from flexmech.service.jobs.grids import grid_shape, load_paths
from flexmech.service.jobs.kinds import kind_named
from flexmech.service.jobs.store import JobStore
from flexmech.service.jobs.sweep_options import SweepSpec

H = "/sections/flexure/h"


@pytest.fixture
def spec():
    return {
        "document": json.loads((EXAMPLES / "gripper.json").read_text()),
        "parameters": [{"path": H, "values": [0.004, 0.005]}, {"path": ACTUATION, "values": [0, 10, 20]}],
        "continuation": ACTUATION,
        "outputs": ["end_effector.x"],
    }


def test_cartesian_load_paths_run_along_the_continuation_axis(spec):
    typed = SweepSpec.model_validate(spec)
    _, shape = grid_shape(typed.parameters, typed.grid)
    assert shape == (2, 3)
    assert load_paths([H, ACTUATION], "cartesian", ACTUATION, shape) == [[0, 1, 2], [3, 4, 5]]
    # force first: each path holds h and walks the force
    assert load_paths([ACTUATION, H], "cartesian", ACTUATION, (3, 2)) == [[0, 2, 4], [1, 3, 5]]
    assert load_paths([ACTUATION, H], "cartesian", None, (3, 2)) == [[i] for i in range(6)]


def test_resumed_load_path_starts_from_the_last_converged_stored_state(spec):
    kind = kind_named("sweep")
    plan = kind.prepare(spec, Limits()).meta
    finished = {
        0: {"status": "converged", "z": [1.0]},
        1: {"status": "not_converged", "z": [9.0]},
        3: {"status": "converged", "z": [2.0]},
    }
    tasks = kind.tasks(spec, plan, finished, chunk_size=8)
    assert [(t["indices"], t["guess"], t["line"]) for t in tasks] == [([2], [1.0], 0), ([4, 5], [2.0], 1)]


def test_a_task_in_a_worker_reuses_its_mechanism_and_functions(spec):
    kind = kind_named("sweep")
    plan = kind.prepare(spec, Limits()).meta
    task = kind.tasks(spec, plan, {}, chunk_size=8)[0]
    kind.run(spec, task)
    built, compiled = graphs_for.cache_info().misses, sweep_kind._mechanism.cache_info().misses
    points = kind.run(spec, task)
    assert graphs_for.cache_info().misses == built
    assert sweep_kind._mechanism.cache_info().misses == compiled
    assert [i for i, _ in points] == [0, 1, 2] and all(p["status"] == "converged" for _, p in points)


@pytest.mark.parametrize(
    "change, pointer, message",
    [
        (
            lambda s: s.update(grid="zip"),
            "/parameters",
            "a zip grid needs equally many values per parameter (got 2, 3)",
        ),
        (
            lambda s: s.update(continuation="/loads/other"),
            "/continuation",
            "'/loads/other' is not one of the swept paths",
        ),
        (lambda s: s["parameters"].append({"path": H, "values": [1]}), "/parameters", "a path is listed twice"),
        (lambda s: s["parameters"][0].update(path="/sections/flexure/q"), "/parameters/0/path", "not a numeric field"),
        (lambda s: s.update(outputs=["jaw.x"]), "/outputs/0", "unknown output 'jaw.x'"),
        (lambda s: s["parameters"][1].update(values=[float("nan")]), "/parameters/1/values/0", "finite number"),
        (lambda s: s.update(grid="hexagonal"), "/grid", "Input should be 'cartesian' or 'zip'"),
    ],
)
def test_bad_sweep_specs_name_the_field(spec, change, pointer, message):
    change(spec)
    with pytest.raises(MechanismError) as info:
        kind_named("sweep").prepare(spec, Limits())
    assert info.value.pointer == pointer and message in info.value.problem


def test_store_keeps_the_first_copy_of_a_point(tmp_path):
    store = JobStore(f"sqlite:///{tmp_path / 'jobs.db'}")
    job = store.create("sweep", "owner", {"x": 1}, {}, total=2)
    assert store.add_points(job.id, [(0, {"status": "converged", "v": 1.0})]) == 1
    assert store.add_points(job.id, [(0, {"status": "converged", "v": 2.0}), (1, {"status": "singular"})]) == 1
    assert store.points(job.id) == {0: {"status": "converged", "v": 1.0}, 1: {"status": "singular"}}
    stored = store.get(job.id)
    assert (stored.done, stored.failed_points) == (2, 1)
    assert store.finish(job.id, "cancelled") and not store.finish(job.id, "succeeded")
    assert store.get(job.id).status == "cancelled"
