"""A simulation's report reads its outputs and shapes from graphs of their own
(models.graph.assembly: Graphs.prefer_reporting), never building the residual form and its tangent
(the most of a large structure's build): the same numbers as the residual form's graphs, and
a statics analysis of the same structure afterwards still builds and solves its own."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import EXAMPLES

from flexmech.models import compile_mechanism, load_document
from flexmech.models.graph.assembly import build_functions
from flexmech.service.dynamics.run import run_simulation, simulation_spec
from flexmech.service.dynamics.state_map import state_map
from flexmech.service.solvers.equilibrium import solve_equilibrium


def _rod(intervals: int):
    doc = json.loads((EXAMPLES / "rod_free_vibration.json").read_text())
    doc["elements"]["rod"]["intervals"] = intervals  # a count no other test builds: the process has no graphs of it
    return compile_mechanism(load_document(doc))


def _kinds(cache) -> list[str]:
    return sorted(
        "reporting" if folder.name.endswith("-reporting") else "whole" for folder in (cache / "graphs").iterdir()
    )


def test_a_simulation_reports_from_the_outputs_graphs_alone(tmp_path, monkeypatch):
    monkeypatch.setenv("FLEXMECH_CACHE_DIR", str(tmp_path))
    mech = _rod(5)
    wanted = ["bodies.tip.x", "bodies.tip.y", "elements.rod.angle_end", "elements.rod.energy"]
    history, report = run_simulation(mech, simulation_spec(mech, {"until": 0.02, "shapes": True, "outputs": wanted}))
    assert report["status"] == "finished"
    assert _kinds(tmp_path) == ["reporting"]  # the residual form was never built (nor saved)

    whole, meta = build_functions(mech.structure)
    assert list(mech.graphs.output_names) == meta["output_names"]
    form = mech.graphs.energy_form
    z = form.to_state(history.x[-1], history.lam[-1])
    expected = np.asarray(whole["outputs"](z, history.p[-1])).ravel()
    for name in wanted:
        unit = mech.nd_per_doc(meta["output_kinds"][meta["output_names"].index(name)])
        assert report["outputs"][name][-1] == pytest.approx(
            expected[meta["output_names"].index(name)] / unit, rel=1e-12, abs=1e-15
        )
    line = np.asarray(whole["shapes"](z, history.p[-1])[0]) / mech.nd_per_doc("length")
    assert np.allclose(np.array(report["shapes"][-1]["rod"]), line, rtol=1e-12, atol=1e-15)


def test_statics_after_a_simulation_builds_the_whole_form(tmp_path, monkeypatch):
    monkeypatch.setenv("FLEXMECH_CACHE_DIR", str(tmp_path))
    mech = _rod(7)
    _, report = run_simulation(mech, simulation_spec(mech, {"until": 0.02}))
    result = solve_equilibrium(mech)
    assert result.status == "converged"
    assert _kinds(tmp_path) == ["reporting", "whole"]
    # the run starts in the static equilibrium under the hold (found by Newton on the element
    # kernels): the dense residual form's Newton finds the same
    names = list(mech.graphs.output_names)
    y = np.asarray(mech.graphs.outputs(result.z, mech.p())).ravel()
    for name in ("bodies.tip.x", "bodies.tip.y", "bodies.tip.angle"):
        kind = mech.graphs.output_kinds[names.index(name)]
        assert report["outputs"][name][0] == pytest.approx(y[names.index(name)] / mech.nd_per_doc(kind), rel=1e-9)


@pytest.mark.parametrize(
    "example",
    [
        "rod_free_vibration.json",
        "four_bar_dynamics.json",
        "slider_crank_dynamics.json",
        "rod_tip_mass_gravity.json",
        "spinning_rod_case1.json",
    ],
)
def test_the_state_map_is_the_energy_forms(example):
    """A report places the kernels' state in z by service.dynamics.state_map, from element counts;
    the energy form places it by building every element's terms: they must agree."""
    mech = compile_mechanism(load_document(EXAMPLES / example))
    form, light = mech.graphs.energy_form, state_map(mech.structure)
    assert light.x_in_state == form.x_in_state and light.multipliers_in_state == form.multipliers_in_state
    rng = np.random.default_rng(4)
    x, lam = rng.standard_normal(len(form.x_in_state)), rng.standard_normal(len(form.multipliers_in_state))
    np.testing.assert_array_equal(light.to_state(x, lam), form.to_state(x, lam))


def test_a_time_limited_run_stops_stepping_early_enough_to_make_its_report():
    """The stepping's stop leaves REPORT_RESERVE times the measured cost of one kept state's
    records per state kept so far: 6500 states of a 64-element rod once took 0.8 s to report
    after the stepping had used the whole limit, and the server replaced its worker."""
    import time

    from flexmech.service.analyses.simulate import _leaving_time_for_the_report

    mech = compile_mechanism(load_document(EXAMPLES / "rod_free_vibration.json"))
    spec = simulation_spec(mech, {"until": 1.0, "every": 2})
    end = time.monotonic() + 3600.0  # an hour left
    stop, progress = _leaving_time_for_the_report(mech, spec, end)
    assert not stop()  # nothing kept yet: the whole hour is the stepping's
    progress(0.5, 1000)
    assert not stop()  # 500 kept states take far less than an hour to report
    progress(0.9, 10**12)  # so many kept states that their report would outlast the hour
    assert stop()
