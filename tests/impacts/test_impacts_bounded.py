"""An event-driven run holds a bounded number of states however long it runs
(service.impacts.kept_rows), and loses no contact event doing so."""

from __future__ import annotations

import numpy as np
import pytest
from impact_cases import csfh, parsed

import flexmech.service.impacts.stepping as stepping
from flexmech.service.impacts.kept_rows import KeptRows
from flexmech.service.impacts.run import run_impacts


def test_kept_rows_stay_within_the_cap_spread_over_the_run_with_every_event():
    rows = KeptRows(cap=100, event_column=1)
    events = {37, 1234, 1235, 9999}
    for start in range(0, 10_000, 250):
        block = np.zeros((250, 2))
        block[:, 0] = np.arange(start, start + 250)
        block[[k - start for k in events if start <= k < start + 250], 1] = 1.0
        rows.add(block)
    held = rows.rows()
    assert rows.seen == 10_000 and len(held) == len(rows) <= 100
    assert events <= set(held[:, 0].astype(int))
    assert held[0, 0] == 0 and held[-1, 0] == 9_999  # the start and the end
    gaps = np.diff(held[:, 0])
    assert gaps.max() <= 2 * rows.stride and np.all(gaps > 0)  # spread, in order


def test_only_events_may_go_past_the_cap():
    rows = KeptRows(cap=10, event_column=1)
    rows.add(np.column_stack([np.arange(30.0), np.ones(30)]))  # every row an event
    assert len(rows) == 30


def test_a_capped_run_reports_the_same_impacts_and_steps(monkeypatch):
    document, spec = parsed(csfh("6.3", until=0.5))
    full = run_impacts(document, spec)[1]
    monkeypatch.setattr(stepping, "KEPT_EVENT_ROWS", 200)
    capped = run_impacts(document, spec)[1]
    assert full["steps"] > 500 and capped["steps"] == full["steps"]
    assert len(capped["times"]) < 200 + len(full["events"]) + 2 < len(full["times"])
    assert capped["events"] == full["events"]
    without_peaks = [{k: v for k, v in hit.items() if k != "peak_force"} for hit in full["impacts"]]
    assert [{k: v for k, v in hit.items() if k != "peak_force"} for hit in capped["impacts"]] == without_peaks
    # a peak is the largest force among the held states: holding 200 of some 1700 lowers it a little
    for hit, whole in zip(capped["impacts"], full["impacts"]):
        assert 0.9 * whole["peak_force"] < hit["peak_force"] <= whole["peak_force"]
    assert len(full["impacts"]) >= 3
    assert "held" in capped["message"] and f"of {full['steps']} steps" in capped["message"]
    assert capped["time_reached"] == full["time_reached"]
    assert capped["energy_balance_error"] == pytest.approx(full["energy_balance_error"], rel=0.5)


def test_a_thinned_report_evaluates_the_energies_of_its_own_states():
    document, spec = parsed(csfh("6.3", until=0.05, scheme="moreau", step=1e-5))
    every = run_impacts(document, spec.model_copy(update={"max_points": 100_000}))[1]
    thinned = run_impacts(document, spec.model_copy(update={"every": 50}))[1]
    assert len(thinned["times"]) == len(thinned["energies"]["kinetic"]) == 5000 // 50 + 1
    index = [every["times"].index(t) for t in thinned["times"]]
    for name, values in thinned["energies"].items():
        np.testing.assert_allclose(values, np.array(every["energies"][name])[index], rtol=1e-12, atol=1e-15)
