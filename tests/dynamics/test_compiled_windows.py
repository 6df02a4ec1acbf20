"""A structure's window of time steps compiled as a whole (service.kernels.windows): C glue that
calls the compiled chain kernels by name. It must step exactly as the same window with its glue
interpreted, be shared by a renamed structure (its key is the graph, not the names), and come
from the build queue in a server, found by a running engine without a restart."""

from __future__ import annotations

import json
from collections import OrderedDict

import numpy as np
import pytest
from conftest import EXAMPLES

from flexmech.models import compile_mechanism, load_document
from flexmech.service.dynamics import engine as engine_module
from flexmech.service.dynamics.histories import read_histories
from flexmech.service.dynamics.run import scheme_of, simulation_spec, start_shape
from flexmech.service.dynamics.stepping import WINDOW, StepRunner, start_of
from flexmech.service.kernels.build import BuildLimits, Compiler
from flexmech.service.kernels.needs import builds_of, window_builds
from flexmech.service.kernels.queue import Builder, accept_requests, queue_dir


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """A cache of this module's own, with the cheapest kernels compiled once for all its tests."""
    with pytest.MonkeyPatch.context() as patch:
        folder = tmp_path_factory.mktemp("windows") / "cache"
        patch.setenv("FLEXMECH_CACHE_DIR", str(folder))
        patch.setattr(engine_module, "_engines", OrderedDict())  # none on another module's libraries
        _build_kernels(_rod())
        yield folder
        accept_requests(False)


def _rod(rename: bool = False, intervals: int = 4, scheme: str = "generalized_alpha"):
    """The rod of Example I.1 on the cheapest kernels there are (linear elements, no shear or
    axial strain: a second or two of gcc)."""
    doc = json.loads((EXAMPLES / "rod_free_vibration.json").read_text())
    doc["elements"]["rod"].update(degree=1, shear=False, axial=False, intervals=intervals)
    doc["simulate"]["scheme"] = scheme
    if rename:
        doc["elements"]["beam"] = doc["elements"].pop("rod")
        doc["bodies"]["end"] = doc["bodies"].pop("tip")
        doc["elements"]["beam"]["to"] = "end"
        doc["loads"]["hold"]["body"] = "end"
        doc["outputs"] = {}
    return compile_mechanism(load_document(doc))


def _build_kernels(mech) -> None:
    compiler = Compiler()
    for b in builds_of(mech):
        for _, fn, target in b.functions:
            assert compiler.build(fn, target, BuildLimits()).ok


def _first_window(mech, steps: int = WINDOW):
    """(runner, the inputs of a window of `steps` from the static start)."""
    spec = simulation_spec(mech, {"until": 0.1})
    histories = read_histories(mech, spec.histories, spec.until)
    x0, _ = start_shape(mech, spec, histories)
    p, scheme = mech.p(), scheme_of(spec)
    start = start_of(mech.structure, p, x0, 0 * x0, histories, 0.0, scheme)
    runner = StepRunner(mech.structure, p, spec.step, scheme, 0.0, histories, spec.until, 1)
    P, PD, PDD = histories.at_times(p, runner.column_times(0.0, spec.step, steps, steps))
    return runner, [start.state, spec.step, P, PD, PDD, 0.0, runner.mask, steps, *runner.data]


def test_a_renamed_structure_shares_the_window_and_another_count_does_not(cache):
    mech, renamed, longer = _rod(), _rod(rename=True), _rod(intervals=5)
    targets = [window_builds(m)[0].functions[0][2] for m in (mech, renamed, longer)]
    assert targets[0] == targets[1]
    assert targets[2] != targets[0]


def test_the_queue_builds_a_window_that_steps_as_its_interpreted_glue_does(cache, monkeypatch):
    """A run in a process that takes build requests asks for its window and goes on with the
    glue interpreted; the builder compiles it (linked against the kernels); the running engine
    then switches to it, and the compiled window takes the same Newton iterations to the same
    states as the interpreted glue."""
    monkeypatch.setattr(engine_module, "RECHECK", 0.0)
    mech = _rod()
    accept_requests(True)
    runner, args = _first_window(mech)
    engine = runner.engine
    assert not engine.window(WINDOW).is_a("External")
    [request] = [json.loads(p.read_text()) for p in queue_dir().glob("*.json")]
    assert request["kind"] == "function" and len(request["link"]) == 5
    assert request["library"] == str(window_builds(mech)[0].functions[0][2])  # as `flexmech build` names it
    Builder(BuildLimits()).run_one(next(queue_dir().glob("*.json")))
    assert not list(queue_dir().glob("*.json"))
    native = engine.window(WINDOW)
    assert native.is_a("External")
    S_native, _, norms, iterations = (np.asarray(q) for q in native(*args))
    S_glue, _, _, iterations_glue = (np.asarray(q) for q in engine.glue_window(WINDOW)(*args))
    assert np.all(norms <= engine_module.WINDOW_ACCEPTANCE) and iterations.sum() > WINDOW  # real Newton work
    np.testing.assert_array_equal(iterations, iterations_glue)
    np.testing.assert_allclose(S_native, S_glue, rtol=0, atol=1e-12 * np.abs(S_glue).max())


def test_an_sdirk4_window_holds_a_window_s_solves_and_compiled_steps_as_its_glue(cache):
    """sdirk4's window is a fifth as long (four steps of five stages: the implicit solves, and the
    glue, of twenty generalized-alpha steps); `flexmech build` compiles it, and it takes the
    same iterations to the same states as its glue interpreted, with the loads at the stages'
    times."""
    mech = _rod(scheme="sdirk4")
    [build] = window_builds(mech)
    [(_, fn, target)] = build.functions
    assert fn.name() == f"kernel_window_{WINDOW // 5}"
    assert Compiler().build(fn, target, BuildLimits(), link=build.link).ok
    runner, args = _first_window(mech, 4)
    assert runner.window_steps == WINDOW // 5
    assert args[2].shape[1] == 20
    native = runner.engine.window(4)
    assert native.is_a("External")
    S_native, _, norms, iterations = (np.asarray(q) for q in native(*args))
    S_glue, _, _, iterations_glue = (np.asarray(q) for q in runner.engine.glue_window(4)(*args))
    assert np.all(norms <= engine_module.WINDOW_ACCEPTANCE) and iterations.sum() > 20
    np.testing.assert_array_equal(iterations, iterations_glue)
    np.testing.assert_allclose(S_native, S_glue, rtol=0, atol=1e-12 * np.abs(S_glue).max())
