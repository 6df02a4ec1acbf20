"""A request's document is compiled once (service.requests keeps compiled mechanisms by the
document's text, model and limits); its overrides are values over the kept mechanism, and any
change to the document or the model compiles it again."""

from __future__ import annotations

import copy

import pytest

import flexmech.service.requests as requests
from flexmech.service import solve_equilibrium
from flexmech.service.costs import Limits

ACTUATION = "/loads/actuation/force/1"


@pytest.fixture
def compiles(monkeypatch):
    """The compilations made, counted (the cache emptied first)."""
    monkeypatch.setattr(requests, "_COMPILED", type(requests._COMPILED)())
    made = []
    real = requests._compile

    def counted(*args):
        made.append(args)
        return real(*args)

    monkeypatch.setattr(requests, "_compile", counted)
    return made


def closing_x(mech) -> float:
    return solve_equilibrium(mech).outputs()["end_effector.x"]


def test_a_document_is_compiled_once_and_its_overrides_still_count(compiles, gripper_dict):
    document = gripper_dict
    first = requests.compile_request(document, overrides={ACTUATION: 20.0})
    second = requests.compile_request(copy.deepcopy(document), overrides={ACTUATION: 60.0})
    assert len(compiles) == 1
    assert first.value(ACTUATION) == 20.0 and second.value(ACTUATION) == 60.0
    fresh = requests._compile(document, None, Limits()).with_values({ACTUATION: 60.0})
    assert closing_x(second) == pytest.approx(closing_x(fresh), rel=1e-12)
    assert closing_x(first) != pytest.approx(closing_x(second), rel=1e-3)


def test_another_document_model_or_limits_compiles_again(compiles, gripper_dict):
    document = gripper_dict
    requests.compile_request(document)
    stiffer = copy.deepcopy(document)
    stiffer["sections"]["flexure"]["h"] = "7.5 um"  # from 5 um
    thicker = requests.compile_request(stiffer, overrides={ACTUATION: 50.0})
    requests.compile_request(document, model="linear")
    requests.compile_request(document, limits=Limits(max_elements=50))
    assert len(compiles) == 4
    base = requests.compile_request(document, overrides={ACTUATION: 50.0})
    assert len(compiles) == 4  # the first one, kept

    def travel(mech):  # the jaw's travel under 50 uN
        return closing_x(mech) - closing_x(mech.with_values({ACTUATION: 0.0}))

    assert 0 < abs(travel(thicker)) < abs(travel(base)) / 2  # 1.5 times thicker: over 3 times stiffer


def test_the_cache_keeps_a_bounded_number_of_mechanisms(compiles, monkeypatch, gripper_dict):
    monkeypatch.setattr(requests, "COMPILED_KEPT", 3)
    document = gripper_dict
    for k in range(5):
        changed = copy.deepcopy(document)
        changed["description"] = f"variant {k}"
        requests.compile_request(changed)
    assert len(requests._COMPILED) == 3 and len(compiles) == 5
