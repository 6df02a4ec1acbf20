"""The tolerance analysis on the seed-000 gripper with its flexure width toleranced (issue 51,
acceptance 1, 2 and 5): first order against central differences of flexmech's own solves, Monte
Carlo against first order where the response is near linear (and the report saying where it is
not), the yield recounted from independently solved samples, and bad tolerance data refused
naming the field."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import EXAMPLES

import flexmech
from flexmech.models import MechanismError
from flexmech.service.analysis import run_analysis
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.tolerances.fields import resolve_scatter

DOCUMENT = json.loads((EXAMPLES / "gripper_tolerances.json").read_text())
H, FORCE, TIP = "/sections/flexure/h", "/loads/actuation/force/1", "end_effector.x"
SIGMA = 1e-4  # mm: 0.1 um


def gripper(sigma: str = "0.1 um", **tolerances) -> flexmech.Mechanism:
    document = json.loads(json.dumps(DOCUMENT))
    document["tolerances"]["fields"][H] = {"sigma": sigma}
    document["tolerances"].update(tolerances)
    return flexmech.load(document)


def tolerance(mech, **options) -> dict:
    return run_analysis(mech, "tolerance", NewtonOptions(), {"outputs": [TIP], **options})


def closing_force(mech) -> float:
    found = flexmech.solve_for_target(mech, FORCE, TIP, 0.0)
    assert found.status == "converged"
    return found.value


def tip_under_load(mech) -> float:
    state = flexmech.solve(mech)
    assert state.status == "converged"
    return state.outputs[TIP]


@pytest.fixture(scope="module")
def report():
    return tolerance(gripper(), samples=4000, seed=51)


def test_first_order_standard_deviation_equals_central_differences_times_sigma(report):
    mech, step = gripper(), 2e-6  # mm: 2 nm, 4e-4 of the width (truncation ~1e-7 relative)
    up, down = mech.with_values({H: 0.005 + step}), mech.with_values({H: 0.005 - step})
    for name, solve in ((FORCE, closing_force), (TIP, tip_under_load)):
        by_differences = abs(solve(up) - solve(down)) / (2 * step) * SIGMA
        assert report["responses"][name]["first_order"]["std"] == pytest.approx(by_differences, rel=1e-4)
    assert report["responses"][FORCE]["first_order"]["std"] == pytest.approx(4.622, rel=1e-3)  # uN: 6 % of 77 uN
    contribution = report["responses"][FORCE]["first_order"]["contributions"][0]
    assert contribution["source"] == H and contribution["share"] == 1.0


def test_monte_carlo_agrees_with_first_order_where_near_linear(report):
    assert report["samples"] == 4000 and report["unsolved_samples"] == 0
    for name in (FORCE, TIP):
        entry = report["responses"][name]
        assert entry["linearity"]["near_linear"], entry["linearity"]["verdict"]
        sampled = entry["monte_carlo"]
        assert sampled["agrees_with_first_order"], sampled["agreement"]
        assert abs(sampled["mean"] - entry["nominal"]) <= 3 * sampled["mean_error"]
        assert abs(sampled["std"] - entry["first_order"]["std"]) <= 3 * sampled["std_error"]
        assert sampled["std_error"] == pytest.approx(sampled["std"] / math.sqrt(2 * 3999))


def test_the_report_says_where_the_response_is_not_linear():
    """At 0.5 um the tip's compliance (about 1/h^3) curves: first order misses the mean, and the
    curvature the report measures predicts the samples' mean shift."""
    wide = tolerance(gripper("0.5 um"), samples=4000, seed=51)["responses"][TIP]
    assert not wide["linearity"]["near_linear"] and "not linear" in wide["linearity"]["verdict"]
    sampled = wide["monte_carlo"]
    assert not sampled["agrees_with_first_order"] and sampled["agreement"].startswith("differs from first order")
    shift = sampled["mean"] - wide["nominal"]
    assert shift < -10 * sampled["mean_error"]  # far beyond the statistical error
    assert wide["linearity"]["second_order_shift"] == pytest.approx(shift, abs=3 * sampled["mean_error"])


def test_yield_is_the_share_of_independently_solved_samples_meeting_the_specs():
    mech = gripper()
    found = tolerance(mech, samples=60, seed=7)
    scatter = resolve_scatter(mech, mech.document.tolerances)
    widths = 0.005 + scatter.deviations(scatter.draws(60, 7))[:, 0]
    passing = 0
    for k, width in enumerate(widths):
        sample = mech.with_values({H: float(width)})
        force, tip = closing_force(sample), tip_under_load(sample)
        passing += bool(70 <= force <= 85 and tip <= 0.165)
        if k in [s["sample"] for s in found["yield"]["failing_samples"]]:
            assert not (70 <= force <= 85 and tip <= 0.165)
    assert found["yield"]["monte_carlo"] == passing / 60
    assert found["yield"]["failing"] == 60 - passing and 0 < passing < 60
    assert found["yield"]["standard_error"] == pytest.approx(math.sqrt(passing / 60 * (1 - passing / 60) / 60))
    spec = found["responses"][FORCE]
    z = [(b - spec["nominal"]) / spec["first_order"]["std"] for b in (70, 85)]
    normal = 0.5 * (math.erf(z[1] / math.sqrt(2)) - math.erf(z[0] / math.sqrt(2)))
    assert spec["spec_share_first_order"] == pytest.approx(normal, rel=1e-12)


def test_a_seed_gives_the_same_samples_and_other_seeds_others():
    mech = gripper()
    scatter = resolve_scatter(mech, mech.document.tolerances)
    assert np.array_equal(scatter.draws(100, 3)[:40], scatter.draws(100, 3)[:40])
    assert not np.array_equal(scatter.draws(100, 3), scatter.draws(100, 4))
    a, b = tolerance(mech, samples=30, seed=3), tolerance(mech, samples=30, seed=3)
    assert a["responses"][TIP]["monte_carlo"] == b["responses"][TIP]["monte_carlo"]


@pytest.mark.parametrize(
    "fields, pointer, words",
    [
        (
            {"/sections/flexure/q": {"sigma": 1e-4}},
            "/document/tolerances/fields/~1sections~1flexure~1q",
            "not a numeric field",
        ),
        ({"/name": {"sigma": 1e-4}}, "/document/tolerances/fields/~1name", "not a numeric field"),
        ({H: {"sigma": -1e-4}}, "/tolerances/fields/~1sections~1flexure~1h", "sigma must be positive"),
        ({H: {"sigma": "-0.1 um"}}, "/document/tolerances/fields/~1sections~1flexure~1h/sigma", "must be positive"),
        ({H: {"sigma": "1.5 um"}}, "/document/tolerances/fields/~1sections~1flexure~1h/sigma", "probability 0.00043"),
        (
            {H: {"plus_minus": "5 um"}},
            "/document/tolerances/fields/~1sections~1flexure~1h/plus_minus",
            "out of its range",
        ),
        ({H: {"sigma": "0.1 uN"}}, "/document/tolerances/fields/~1sections~1flexure~1h/sigma", "is not a length"),
        ({H: {"sigma": 1e-4, "plus_minus": 1e-4}}, "/tolerances/fields/~1sections~1flexure~1h", "one of them"),
    ],
)
def test_bad_tolerance_data_names_the_field(fields, pointer, words):
    document = json.loads(json.dumps(DOCUMENT))
    document["tolerances"]["fields"] = fields
    with pytest.raises(MechanismError) as info:
        tolerance(flexmech.load(document), samples=0)
    assert info.value.pointer == pointer and words in info.value.problem


def test_a_spec_on_an_unknown_response_names_it():
    mech = gripper(specs={"end_efector.x": {"max": 1}})
    with pytest.raises(MechanismError) as info:
        tolerance(mech, samples=0)
    assert info.value.pointer == "/document/tolerances/specs/end_efector.x"
    assert "unknown response 'end_efector.x'" in info.value.problem


def test_frequencies_scatter_as_their_exact_derivatives_say():
    document = json.loads((EXAMPLES / "gripper_modes.json").read_text())
    document["tolerances"] = {"fields": {H: {"sigma": "0.1 um"}}}
    mech = flexmech.load(document)
    found = run_analysis(mech, "tolerance", NewtonOptions(), {"of": "modes", "count": 2, "samples": 8, "seed": 1})
    step = 2e-6
    up, down = (
        [
            m["frequency"]
            for m in flexmech.modes(mech.with_values({H: 0.005 + s}), count=2, shapes=False).report["modes"]
        ]
        for s in (step, -step)
    )
    for k in (1, 2):
        by_differences = abs(up[k - 1] - down[k - 1]) / (2 * step) * SIGMA
        entry = found["responses"][f"frequency.{k}"]
        assert entry["unit"] == "Hz" and entry["first_order"]["std"] == pytest.approx(by_differences, rel=1e-4)
    assert found["samples"] == 8 and found["unsolved_samples"] == 0


def test_contact_forces_scatter_as_their_exact_derivatives_say():
    """The jaw pressed onto its fixture, the fixture's place toleranced (0.05 mm): the normal
    force's first order against central differences of contact solves."""
    document = json.loads((EXAMPLES / "gripper_jaw_contact.json").read_text())
    centre = "/contacts/objects/fixture/centre/0"
    document["contacts"]["objects"]["fixture"]["centre"][0] = 67.4
    document["tolerances"] = {"fields": {centre: {"sigma": 0.05}}}
    mech = flexmech.load(document)
    found = run_analysis(mech, "tolerance", NewtonOptions(), {"of": "contact", "samples": 10, "seed": 1})
    force = "contacts.insertion.normal_force"

    def normal_force(x: float) -> float:
        report = run_analysis(mech.with_values({centre: x}), "contact", NewtonOptions())
        return report["pairs"]["insertion"]["normal_force"]

    step = 1e-3
    by_differences = abs(normal_force(67.4 + step) - normal_force(67.4 - step)) / (2 * step) * 0.05
    entry = found["responses"][force]
    assert entry["nominal"] == pytest.approx(normal_force(67.4), rel=1e-6) and entry["nominal"] > 1.0
    assert entry["first_order"]["std"] == pytest.approx(by_differences, rel=1e-3)
    assert found["unsolved_samples"] == 0 and entry["monte_carlo"]["samples"] == 10
