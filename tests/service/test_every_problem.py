"""A request or a document with problems in several fields: the 422 names one field in its
message and pointer, as every error does, and lists every field with its own problem in
`problems` (the workbench marks each at its line); one problem keeps the plain shape."""

from __future__ import annotations

import json

import httpx
import pytest
from conftest import EXAMPLES

from flexmech.models import MechanismError, load_document

NUMBER = "expected a number (or a quantity string like '25 um', at most 100 characters), got true"


def three_problems() -> dict:
    """The gripper with a body's position, a beam's radius and a load's field wrong."""
    document = json.loads((EXAMPLES / "gripper.json").read_text())
    document["bodies"]["input"]["position"] = "here"
    document["elements"]["a"]["radius"] = True
    document["loads"]["actuation"]["colour"] = "red"
    return document


def test_the_document_reader_lists_every_field_with_its_problem():
    with pytest.raises(MechanismError) as info:
        load_document(three_problems())
    error = info.value
    assert error.pointer == "/loads/actuation/colour"  # an unknown field first: a typo explains the rest
    assert str(error) == "/loads/actuation/colour: unknown field 'colour' (and 2 more fields with problems)"
    assert dict(error.problems) == {
        "/loads/actuation/colour": "unknown field 'colour'",
        "/bodies/input/position": "Input should be a valid tuple",
        "/elements/a/radius": NUMBER,
    }
    assert error.problems[0] == ("/loads/actuation/colour", "unknown field 'colour'")


def test_a_document_with_three_problems_gives_three_problems_at_their_pointers(api_server):
    r = httpx.post(f"{api_server.url}/v1/drawings", json={"document": three_problems()}, timeout=60)
    assert r.status_code == 422, r.text
    error = r.json()["error"]
    assert error["code"] == "invalid_input" and error["pointer"] == "/document/loads/actuation/colour"
    assert (
        error["message"] == "/document/loads/actuation/colour: unknown field 'colour' (and 2 more fields with problems)"
    )
    assert error["problems"] == [
        {"pointer": "/document/loads/actuation/colour", "message": "unknown field 'colour'"},
        {"pointer": "/document/bodies/input/position", "message": "Input should be a valid tuple"},
        {"pointer": "/document/elements/a/radius", "message": NUMBER},
    ]


def test_a_request_with_three_problems_gives_three_problems_at_their_pointers(api_server):
    body = {"example": "gripper", "analysis": "equilibrium", "model": "straight", "overrides": [1], "colour": 1}
    r = httpx.post(f"{api_server.url}/v1/solve", json=body, timeout=60)
    assert r.status_code == 422, r.text
    error = r.json()["error"]
    assert error["code"] == "invalid_request" and error["pointer"] == "/colour"
    assert error["message"] == "/colour: unknown field 'colour' (and 2 more fields with problems)"
    pointers = [p["pointer"] for p in error["problems"]]
    assert pointers[0] == "/colour" and sorted(pointers) == ["/colour", "/model", "/overrides"]
    assert all(p["message"] for p in error["problems"])


def test_one_problem_keeps_the_plain_shape(api_server):
    document = json.loads((EXAMPLES / "gripper.json").read_text())
    document["elements"]["c"]["to"] = "folower"
    r = httpx.post(f"{api_server.url}/v1/drawings", json={"document": document}, timeout=60)
    assert r.status_code == 422
    error = r.json()["error"]
    assert set(error) == {"status", "code", "message", "pointer"}
    assert error["pointer"] == "/document/elements/c/to" and "unknown body 'folower'" in error["message"]
