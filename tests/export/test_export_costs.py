"""An export's iteration options are costed before it runs (issue 53): a tolerance double
precision cannot reach, or a check over the example path that would run for minutes, is a 422
naming the option; the default options of the largest shipped export stay well within."""

from __future__ import annotations

import time

import httpx
import pytest

from flexmech.models import MechanismError
from flexmech.service.costs import EXPORT_CHECK_SECONDS, check_export_iteration

ISSUE = {"example": "gripper", "tolerance": 1e-300, "max_iterations": 1000, "line_search_halvings": 30}


def test_the_issues_export_is_refused_naming_each_option(api_server):
    started = time.perf_counter()
    refused = httpx.post(api_server.url + "/v1/exports", json=ISSUE, timeout=60)
    print(f"\nthe issue's export: {refused.status_code} in {time.perf_counter() - started:.3f} s")
    error = refused.json()["error"]
    assert refused.status_code == 422 and error["pointer"] == "/tolerance"
    assert "1e-300 is below what double precision reaches" in error["message"]
    costly = httpx.post(api_server.url + "/v1/exports", json=dict(ISSUE, tolerance=1e-12), timeout=60)
    error = costly.json()["error"]
    assert costly.status_code == 422 and error["pointer"] == "/max_iterations"
    # 100 points x 2 runs x (1 + 1000 x 31) calls of 9 unknowns at 52 us: about 322 s
    assert "= 6200200 kernel calls of 9 unknowns" in error["message"] and "the limit is 60 s" in error["message"]
    started = time.perf_counter()
    exact = httpx.post(
        api_server.url + "/v1/exports", json={"example": "gripper_exact", "tolerance": 1e-16}, timeout=120
    )
    print(f"gripper_exact at tolerance 1e-16: {exact.status_code} in {time.perf_counter() - started:.3f} s")
    assert exact.status_code == 422 and exact.json()["error"]["pointer"] == "/tolerance"


def test_default_options_fit_and_halvings_are_named_when_they_drive_the_cost():
    check_export_iteration(137, 30, 6, 1e-12, contact=False)  # gripper_exact: 42,200 calls, about 17 s at worst
    check_export_iteration(400, 30, 6, 1e-12, contact=False)  # the largest export allowed: about 47 s
    with pytest.raises(MechanismError) as halvings:
        check_export_iteration(137, 30, 30, 1e-12, contact=True)
    assert halvings.value.pointer == "/line_search_halvings"
    assert f"the limit is {EXPORT_CHECK_SECONDS:.0f} s" in halvings.value.problem
    check_export_iteration(9, 30, 6, 1e-14, contact=False)  # the finest tolerance taken
