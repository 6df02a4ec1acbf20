"""A simulation to an accuracy target (service.dynamics.accuracy): the refinements it picks, its
estimates against an independent reference, a target out of reach as a result, and its refusals."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import EXAMPLES
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service.analyses import ANALYSES
from flexmech.service.analyses.base import AnalysisRequest
from flexmech.service.dynamics.accuracy import Plan, differences, link_intervals, mechanism_of

TIP = ["bodies.tip.x", "bodies.tip.y"]


def rod(intervals: int = 2, **simulate):
    """The rod's release, 0.3 s, coarse: 2 elements in 4 ms steps."""
    document = json.loads((EXAMPLES / "rod_free_vibration.json").read_text())
    document["elements"]["rod"]["intervals"] = intervals
    document["simulate"].update({"until": 0.3, "step": 0.004, "every": 1, "outputs": TIP, **simulate})
    return compile_mechanism(load_document(document))


def simulated(mech, **fields) -> dict:
    return ANALYSES.named("simulate").run(mech, AnalysisRequest(given={"simulate": fields}))


def test_a_target_is_met_against_an_independent_reference_and_its_estimates_are_not_low():
    """From 2 elements and 4 ms (about 2e-2 off), a target of 5e-3 refines both until the estimate
    is within it. The run it reports is within the target against sdirk4 at 8 elements and
    0.25 ms (itself about 1e-4 off), and each output's estimate is at least half its error
    there: an estimate that ignored a part (or compared a run with itself) would fail."""
    report = simulated(rod(), accuracy=5e-3)
    accuracy = report["accuracy"]
    assert report["status"] == "finished" and accuracy["met"], report["message"]
    chosen = (accuracy["intervals"]["rod"], accuracy["step"])
    assert chosen != (2, 0.004) and chosen[0] >= 2 and chosen[1] <= 0.004
    reference = simulated(rod(8), scheme="sdirk4", step=2.5e-4)
    errors = differences(report, reference, TIP)
    for name in TIP:
        assert errors[name] <= 5e-3
        assert 0.5 * errors[name] <= accuracy["estimated_errors"][name] <= 5e-3
    first = accuracy["runs"][0]
    assert first == {**first, "intervals": {"rod": 2}, "step": 0.004, "role": "run", "status": "finished"}
    assert {r["role"] for r in accuracy["runs"]} == {"run", "step / 2", "elements x 2"}


def test_a_target_out_of_reach_is_a_result_with_what_was_tried():
    report = simulated(rod(), accuracy=1e-6, max_steps=400)
    assert report["status"] == "accuracy_not_reached"
    assert "the accuracy target 1e-06 was not reached" in report["message"]
    assert "over the limit of 400" in report["message"]
    accuracy = report["accuracy"]
    assert not accuracy["met"] and report["times"][-1] == pytest.approx(0.3)  # the last run that finished
    assert accuracy["runs"][-1]["status"] == "step_limit"
    assert accuracy["intervals"] == {"rod": 2} and min(accuracy["estimated_errors"].values()) > 1e-6


def test_an_accuracy_target_needs_named_outputs_and_link_schemes():
    document = json.loads((EXAMPLES / "rod_free_vibration.json").read_text())
    del document["simulate"]["outputs"]
    mech = compile_mechanism(load_document(document))
    with pytest.raises(MechanismError) as unnamed:
        simulated(mech, accuracy=1e-3, until=0.01)
    assert unnamed.value.pointer == "/simulate/outputs" and "name them" in unnamed.value.problem
    with pytest.raises(MechanismError) as impacts:
        simulated(rod(), accuracy=1e-3, scheme="event_driven")
    assert impacts.value.pointer == "/simulate/accuracy"
    assert "follows its own `tolerance`" in impacts.value.problem


def test_a_refinement_keeps_the_request_s_values():
    """A request's numbers over the document's (here the section's thickness) stay in the
    refined mechanism; only the elements change."""
    mech = rod(3).with_values({"/sections/rod/h": 0.004})
    plan = Plan(link_intervals(mech), 0.004, None).finer_space(mech)
    refined = mechanism_of(mech, plan)
    assert link_intervals(refined) == (("rod", 6),)
    assert refined.value("/sections/rod/h") == pytest.approx(0.004)
    assert np.array_equal(
        [refined.value(p.pointer) for p in mech.parameters], [mech.value(p.pointer) for p in mech.parameters]
    )


def test_the_command_line_prints_the_chosen_discretization_and_each_estimate(tmp_path):
    document = json.loads((EXAMPLES / "rod_free_vibration.json").read_text())
    document["elements"]["rod"]["intervals"] = 2
    document["simulate"].update({"until": 0.3, "step": 0.004, "every": 1, "outputs": TIP})
    path = tmp_path / "rod.json"
    path.write_text(json.dumps(document))
    result = CliRunner().invoke(app, ["simulate", str(path), "--accuracy", "0.05", "--no-build"])
    assert result.exit_code == 0, result.output
    assert "accuracy target 0.05 met: elements rod 2; step 0.004 s; 3 runs" in result.output
    assert "(of 3 runs to the accuracy target)" in result.output
    for name in TIP:
        assert any(line.strip("│ ").startswith(name) for line in result.output.splitlines())
