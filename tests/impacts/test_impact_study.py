"""Seed 004's parametric study compares each run with the nominal one at every step the
nominal run holds, so a Moreau impact (one step long) is seen where it happens, and reports
each run's contacts from its events (service.impacts.study)."""

from __future__ import annotations

import numpy as np
import pytest
from impact_cases import csfh

from flexmech.service.impacts.study import legacy_influence, nominal_run, study_point

TOLERANCE = 0.05
STEP = 1e-5
SLIDING = "/contacts/pairs/conjugate/friction/sliding"


@pytest.fixture(scope="module")
def moreau():
    """Scenario 6.3 with Moreau steps: three contacts in 0.3 s."""
    return csfh("6.3", scheme="moreau", step=STEP, until=0.3)


def onsets(document) -> list[float]:
    full, _ = nominal_run(document, None)
    return [e["time"] for e in full.events if e["kind"] == "contact"]


def test_the_sliding_friction_departs_where_the_contact_first_slides_and_later_for_a_smaller_change(moreau):
    """The first contact sticks (its tangent impulse is within f_a = 0.11 of the normal one),
    so f_d changes nothing there; the second slides. A change of f_d by 0.05 departs at the
    second contact; one of 0.001 changes that contact's friction by under 5 % of its range,
    and departs only later, once the motion has drifted."""
    first, second = onsets(moreau)[:2]
    large = study_point(moreau, None, SLIDING, 0.05, TOLERANCE)
    small = study_point(moreau, None, SLIDING, 0.001, TOLERANCE)
    large_departure = large["influence"]["conjugate.F_T"]["departure"]
    small_departure = small["influence"]["conjugate.F_T"]["departure"]
    assert second <= large_departure <= second + 2 * STEP
    assert small_departure is not None and small_departure > large_departure
    nominal = study_point(moreau, None, None, 0.0, TOLERANCE)["contacts"]["conjugate"]
    for run in (large, small):  # the first contact, which sticks, is the same: where and how hard
        contact = run["contacts"]["conjugate"]
        assert contact["first_contact"] == nominal["first_contact"] == pytest.approx(first)
        assert contact["peak_force"] == nominal["peak_force"]
        assert all(v["departure"] is None or v["departure"] >= second for v in run["influence"].values())


def test_a_larger_pin_meets_the_hole_earlier_and_a_heavier_turn_changes_the_first_impulse(moreau):
    """Seed 004 Table 4's two extremes: a 1 mm larger pin (a smaller clearance) departs before
    the nominal first contact, at its own first contact, with another peak force; 0.001 kg m^2
    more inertia leaves the flight alone and departs at the first impact itself."""
    nominal = study_point(moreau, None, None, 0.0, TOLERANCE)["contacts"]["conjugate"]
    larger = study_point(moreau, None, "/contacts/sites/pin/radius", 0.001, TOLERANCE)
    departure = larger["influence"]["conjugate.F_N"]["departure"]
    assert departure < nominal["first_contact"]
    assert departure == pytest.approx(larger["contacts"]["conjugate"]["first_contact"], abs=2 * STEP)
    assert larger["contacts"]["conjugate"]["peak_force"] != pytest.approx(nominal["peak_force"], rel=1e-3)
    heavier = study_point(moreau, None, "/bodies/hinge/inertia", 0.001, TOLERANCE)
    assert heavier["influence"]["conjugate.F_N"]["departure"] == pytest.approx(nominal["first_contact"], abs=2 * STEP)
    for coordinate in ("hinge.x", "hinge.y"):
        assert heavier["influence"][coordinate]["departure"] is None
    assert heavier["contacts"]["conjugate"]["first_contact"] == pytest.approx(nominal["first_contact"], abs=STEP)


def test_points_stored_with_sampled_series_are_still_compared():
    nominal = {"series": {"a": [0.0, 1.0, 2.0, 3.0]}}
    run = {"series": {"a": [0.0, 1.0, 2.5, 3.0]}}
    influence = legacy_influence(nominal, run, 3.0, 0.1)["a"]
    assert influence["departure"] == 2.0  # the grid: 0, 1, 2, 3 s
    assert influence["max"] == pytest.approx(0.5 / 3)


def test_a_job_resumed_across_versions_answers_with_the_points_it_can_compare():
    """An old point (sampled series) beside a nominal run stored by this version (numbers
    only) cannot be compared: its influence is empty, and the result is still made."""
    from flexmech.service.jobs.impact_study import IMPACT_STUDY

    plan = {
        "runs": [{"path": None, "change": 0.0}, {"path": "/a", "change": 1.0}, {"path": "/a", "change": -1.0}],
        "until": 3.0,
        "tolerance": 0.1,
        "scheme": "moreau",
    }
    nominal = {"status": "finished", "impacts": 3, "seconds": 0.1, "contacts": {}}
    old = {"path": "/a", "change": 1.0, "status": "finished", "impacts": 3, "series": {"a": [0.0, 1.0]}}
    new = {
        "path": "/a",
        "change": -1.0,
        "status": "finished",
        "impacts": 2,
        "contacts": {},
        "influence": {"a": {"departure": 1.0, "rms": 0.2, "max": 0.5}},
    }
    result = IMPACT_STUDY.result({}, plan, {0: nominal, 1: old, 2: new})
    assert result["fields"]["/a"]["+"]["influence"] == {}
    assert result["fields"]["/a"]["-"]["influence"] == new["influence"]
    assert result["ranking"] == [{"path": "/a", "earliest_departure": 1.0, "largest_rms": 0.2}]


def test_a_stopped_run_is_reported_stopped_at_once_and_its_nominal_is_not_kept(moreau):
    """A cancel mid-run (stop() true): no contacts are evaluated at its states (seconds for two
    million of them) and the stopped nominal run is not kept, so the next task runs it whole."""
    stopped = study_point(moreau, None, SLIDING, 0.05, TOLERANCE, stop=lambda: True)
    assert stopped["status"] == "stopped" and stopped["message"].startswith("stopped at t = ")
    assert "contacts" not in stopped
    document = {**moreau, "name": "not kept when stopped"}  # a key of its own among the kept runs
    assert nominal_run(document, None, stop=lambda: True)[0] is None
    full, report = nominal_run(document, None)
    assert report["status"] == "finished" and full is not None and len(onsets(document)) >= 3


def test_histories_evaluated_in_parts_are_the_same_and_a_stop_between_parts_ends_them(monkeypatch):
    """Event-driven csfh (scenario 6.3, 0.3 s): its states' contacts evaluated 64 states per
    mapped call equal those of one call, and a stop() that turns true after the first parts
    ends the run's histories (RunStopped, reported as a stopped run without histories)."""
    import flexmech.service.impacts.report as report_module
    import flexmech.service.impacts.run as run_module
    from flexmech.models.documents.document import MechanismDocument
    from flexmech.service.impacts.run import integrate

    document = MechanismDocument.model_validate(csfh("6.3", until=0.3))
    spec = document.simulate
    model, p, trace = integrate(document, spec)
    whole = report_module.histories(model, spec, trace, p)
    monkeypatch.setattr(report_module, "MAP_COLUMNS", 64)
    assert len(whole.states) > 4 * 64
    parts = report_module.histories(model, spec, trace, p)
    for name, values in whole.pairs.items():
        for quantity, series in values.items():
            assert np.array_equal(parts.pairs[name][quantity], series), (name, quantity)
    assert parts.events == whole.events and parts.impacts == whole.impacts
    looks = iter([False, False])
    with pytest.raises(report_module.RunStopped, match="stopped while evaluating states 128 of"):
        report_module.histories(model, spec, trace, p, stop=lambda: next(looks, True))
    stepped = []  # the run's stepping has ended: its stop() says so from then on

    def integrated(*args):
        done = integrate(*args)
        stepped.append(True)
        return done

    monkeypatch.setattr(run_module, "integrate", integrated)
    full, report = run_module.run_with_histories(document, spec, stop=lambda: bool(stepped))
    assert full is None and report["status"] == "stopped"
    assert report["message"].startswith("stopped while evaluating states 0 of")
