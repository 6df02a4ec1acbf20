"""Bounded text (issue 52): every text field and key of the document and of every request body
has a length limit, and a text over it is refused naming the field and the limit, never echoing
the text. The HTTP cases (a 990,000-character description, a 900,000-character name) are among
tests/abuse_cases.py, sent to a live server by tests/service/test_abuse.py."""

from __future__ import annotations

import copy

import pytest
from conftest import EXAMPLES

from flexmech.api import schemas
from flexmech.api.analysis_requests import request_model
from flexmech.api.app import create_app
from flexmech.models import MechanismDocument, MechanismError, load_document
from flexmech.models.documents import fields
from flexmech.models.documents.text_bounds import MAX_KEY_CHARS, check_text_bounds
from flexmech.service.analyses import ANALYSES
from flexmech.service.jobs.kinds import job_kinds


def unbounded(schema: dict, components: dict, skipped: frozenset[str] = frozenset()) -> list[str]:
    """The JSON paths of every string schema without maxLength (nor enum or const) and of every
    object with additionalProperties whose propertyNames have no maxLength; $refs are followed
    once (into `components`, but not those named in `skipped`)."""
    found, seen = [], set()
    stack: list[tuple[str, object]] = [("#", schema)]
    while stack:
        path, node = stack.pop()
        if isinstance(node, list):
            stack += [(f"{path}/{k}", item) for k, item in enumerate(node)]
            continue
        if not isinstance(node, dict):
            continue
        if "$ref" in node:
            name = node["$ref"].rsplit("/", 1)[1]
            if name not in seen and name not in skipped:
                seen.add(name)
                stack.append((f"#/{name}", components[name]))
            continue
        if node.get("type") == "string" and not {"maxLength", "enum", "const"} & set(node):
            found.append(path)
        extra = node.get("additionalProperties", False)
        if node.get("type") == "object" and extra is not False and "maxLength" not in node.get("propertyNames", {}):
            found.append(f"{path} (its keys)")
        stack += [(f"{path}/{key}", value) for key, value in node.items() if key not in ("examples", "default")]
    return sorted(found)


def test_every_text_and_key_of_the_document_schema_is_bounded():
    schema = MechanismDocument.model_json_schema()
    assert not unbounded(schema, schema.get("$defs", {})), "unbounded: " + ", ".join(
        unbounded(schema, schema.get("$defs", {}))
    )


def _from_elsewhere(thing: object) -> bool:
    return not type(thing).__module__.startswith("flexmech.")


def test_every_text_and_key_of_every_request_body_is_bounded():
    """Every body the app's OpenAPI document takes (the analyses and job kinds registered by other
    test modules are theirs: left out)."""
    schema = create_app().openapi()
    components = schema["components"]["schemas"]
    skipped = frozenset(
        [request_model(a).__name__ for a in ANALYSES if _from_elsewhere(a)]
        + [kind.request_name for kind in job_kinds().values() if _from_elsewhere(kind)]
    )
    found, bodies = [], 0
    for route, operations in schema["paths"].items():
        for method, operation in operations.items():
            for media, content in operation.get("requestBody", {}).get("content", {}).items():
                bodies += 1
                found += [
                    f"{method.upper()} {route} {media}: {p}" for p in unbounded(content["schema"], components, skipped)
                ]
    assert bodies >= 10
    assert not found, "unbounded:\n" + "\n".join(sorted(set(found)))


def test_the_clients_bounds_are_the_documents():
    """api.schemas keeps its own copies (the client does not import the core)."""
    for name in ("MAX_NAME_CHARS", "MAX_DESCRIPTION_CHARS", "MAX_POINTER_CHARS", "MAX_QUANTITY_CHARS"):
        assert getattr(schemas, name) == getattr(fields, name), name
    assert MAX_KEY_CHARS == max(fields.MAX_NAME_CHARS, fields.MAX_POINTER_CHARS, fields.MAX_OUTPUT_CHARS)


def refused(document: dict) -> MechanismError:
    with pytest.raises(MechanismError) as info:
        load_document(document)
    return info.value


def test_a_name_of_201_characters_is_refused_naming_the_field_and_the_limit(gripper_dict):
    assert load_document(dict(gripper_dict, name="n" * 200)).name == "n" * 200
    error = refused(dict(gripper_dict, name="n" * 201))
    assert error.pointer == "/name"
    assert str(error) == "/name: at most 200 characters (got 201)"


def test_a_long_description_is_a_text_too_long_not_a_bad_number(gripper_dict):
    error = refused(dict(gripper_dict, description="d" * 20_001))
    assert str(error) == "/description: at most 20000 characters (got 20001)"
    quantity = copy.deepcopy(gripper_dict)
    quantity["elements"]["a"]["radius"] = "1" * 101
    assert "expected a number (or a quantity string like '25 um', at most 100 characters)" in str(refused(quantity))


def test_a_long_key_is_its_collections_error_and_is_not_echoed(gripper_dict):
    document = copy.deepcopy(gripper_dict)
    document["materials"]["m" * 201] = {"E": 1e9}
    error = refused(document)
    assert str(error) == "/materials: a key of 201 characters: keys here are at most 200 characters"
    assert "m" * 201 not in str(error.problems)


def test_every_text_field_is_bounded_by_its_kind(gripper_dict):
    """A reference to a body, a unit, an expression, a pointer and an output name each by theirs."""
    cases = [
        (lambda d: d["elements"]["a"].update({"from": "b" * 201}), "/elements/a/from", 200),
        (lambda d: d["units"].update(length="m" * 65), "/units/length", 64),
        (
            lambda d: d["elements"]["a"].update(material="m" * 300),
            "/elements/a/material",
            200,
        ),
        (lambda d: d["sweep"].update(path="/" + "p" * 256), "/sweep/path", 256),
        (lambda d: d["sweep"].update(until={"output": "o" * 257, "equals": 0}), "/sweep/until/output", 256),
    ]
    for change, pointer, limit in cases:
        document = copy.deepcopy(gripper_dict)
        change(document)
        error = refused(document)
        assert error.pointer == pointer and f"at most {limit} characters (got " in error.problem, (pointer, error)


def test_the_raw_check_names_the_first_text_over_its_bound(gripper_dict):
    def problem(document: dict) -> tuple[str, str]:
        with pytest.raises(MechanismError) as info:
            check_text_bounds(document, "/document")
        return info.value.pointer, info.value.problem

    assert problem(dict(gripper_dict, description="d" * 990_000)) == (
        "/document/description",
        "at most 20000 characters (got 990000)",
    )
    assert problem(dict(gripper_dict, name="n" * 900_000)) == ("/document/name", "at most 200 characters (got 900000)")
    deep = copy.deepcopy(gripper_dict)
    deep["simulate"] = {"histories": {"/loads/actuation/force/1": "t" * 20_001}}
    assert problem(deep) == (
        "/document/simulate/histories/~1loads~1actuation~1force~11",
        "a text of 20001 characters: no text of a document may be longer than 20000",
    )
    deep["simulate"]["histories"] = {"k" * 300: 1}
    assert problem(deep) == (
        "/document/simulate/histories",
        "a key of 300 characters: keys here are at most 256 characters",
    )
    nested: list = []
    for _ in range(10_000):  # no recursion: a depth the JSON reader would refuse does not overflow it
        nested = [nested]
    check_text_bounds({"bodies": nested})


def test_every_example_loads_and_passes_the_raw_check():
    """The raw check is never stricter than the models: every example passes both."""
    paths = sorted(EXAMPLES.glob("*.json")) + sorted(EXAMPLES.glob("*.yaml"))
    assert len(paths) >= 20
    for path in paths:
        document = load_document(path)
        check_text_bounds(document.to_json_dict())
