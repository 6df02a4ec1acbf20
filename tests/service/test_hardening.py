"""Issue 12's edges, one test each beyond the abusive requests of tests/service/test_abuse.py: bounded
results and counts, strict reading of files and bodies, field checks on design bounds, API
keys, the offline /docs page, the health page, names in pointers, and messages a new user
can act on."""

from __future__ import annotations

import json
import re
import socket
import time

import httpx
import pytest
from abuse_cases import gripper
from conftest import EXAMPLES, Deployment
from typer.testing import CliRunner

from flexmech.api.client import Client
from flexmech.models import MechanismError, compile_mechanism, load_document


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("hardening")
    server = Deployment(
        "sqlite",
        {
            "FLEXMECH_DATA_DIR": str(tmp / "data"),
            "FLEXMECH_WORKERS": "1",
            "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
            "FLEXMECH_API_KEYS": "",
            "FLEXMECH_MAX_RESULT_VALUES": "5000",
            "FLEXMECH_MAX_LOADS": "3",
            "FLEXMECH_HEADER_READ_TIMEOUT": "1",
        },
        tmp,
    ).start()
    yield server
    server.stop()


def error(r: httpx.Response) -> dict:
    return r.json()["error"]


def raw_exchange(url: str, parts: list[bytes], pause: float = 0.0, answer_each: bool = False) -> list[bytes]:
    """Send parts over one connection (pausing between them, or with answer_each reading an
    answer to each part before the next), then read until the server closes it: the answers,
    split at each status line. A server that never closes fails the read's 30 s timeout."""
    host, port = url.removeprefix("http://").split(":")
    with socket.create_connection((host, int(port)), timeout=30) as s:
        received = b""
        for k, part in enumerate(parts):
            if k and answer_each:
                while not _complete(received, k):
                    received += s.recv(65536)
            elif k:
                time.sleep(pause)
            s.sendall(part)
        while chunk := s.recv(65536):
            received += chunk
    return [b"HTTP/1.1" + answer for answer in received.split(b"HTTP/1.1")[1:]]


def _complete(received: bytes, count: int) -> bool:
    """Whether `received` holds `count` whole answers (each with its content-length body)."""
    for _ in range(count):
        head, sep, rest = received.partition(b"\r\n\r\n")
        if not sep:
            return False
        length = int(re.search(rb"content-length: (\d+)", head, re.I).group(1))
        if len(rest) < length:
            return False
        received = rest[length:]
    return True


def test_a_connection_that_does_not_finish_its_headers_is_answered_408_and_closed(server):
    """The header deadline (FLEXMECH_HEADER_READ_TIMEOUT, 1 s here): nothing sent; half a
    request line and a header; a second request's first bytes after an answered one."""
    health = b"GET /v1/health HTTP/1.1\r\nHost: x\r\n\r\n"
    for parts, answered in (
        ([b""], 0),
        ([b"POST /v1/solve HTTP/1.1\r\nHost: x\r\nContent-Type: appl"], 0),
        ([health, b"GET /v1/hea"], 1),
    ):
        answers = raw_exchange(server.url, parts, answer_each=True)
        assert len(answers) == answered + 1, answers
        assert all(a.startswith(b"HTTP/1.1 200") for a in answers[:answered])
        late = answers[-1]
        assert late.startswith(b"HTTP/1.1 408 Request Timeout"), late
        body = json.loads(late.partition(b"\r\n\r\n")[2])["error"]
        assert body["code"] == "request_timeout"
        assert body["message"] == "the request's headers did not arrive within 1 s (FLEXMECH_HEADER_READ_TIMEOUT)"


def test_headers_sent_in_pieces_within_the_deadline_are_served(server):
    answers = raw_exchange(
        server.url, [b"GET /v1/health HTTP/1.1\r\nHo", b"st: x\r\nConnection: close\r\n\r\n"], pause=0.3
    )
    assert len(answers) == 1 and answers[0].startswith(b"HTTP/1.1 200"), answers


# --- 1. bounded work and results -----------------------------------------------------------
def test_stored_results_are_bounded_and_paged(server):
    r = httpx.post(
        server.url + "/v1/sweeps",
        json={
            "example": "gripper",
            "parameters": [{"path": "/loads/actuation/force/1", "start": 0, "stop": 50, "steps": 99}],
        },
    )
    assert r.status_code == 422 and error(r)["pointer"] == "/outputs"
    assert re.match(
        r"/outputs: 100 points x \d+ stored values = \d+: the limit is 5000; keep fewer outputs or points",
        error(r)["message"],
    )
    with Client(server.url) as client:
        job = client.sweep(
            example="gripper",
            outputs=["end_effector.x"],
            parameters=[{"path": "/loads/actuation/force/1", "start": 0, "stop": 50, "steps": 99}],
        )
        assert client.wait(job.id, timeout=120).status == "succeeded"
        whole = client.result(job.id)
        page = client.result(job.id, offset=30, limit=25)
    assert whole.complete and whole.page.total == 100 and len(whole.result.points) == 100
    assert page.page.model_dump() == {"offset": 30, "limit": 25, "returned": 25, "total": 100}
    assert [p.index for p in page.result.points] == list(range(30, 55))
    assert [p.outputs for p in page.result.points] == [p.outputs for p in whole.result.points[30:55]]


def test_counts_of_a_document_are_bounded(server):
    document = gripper()
    document["loads"] |= {f"extra{k}": {"type": "moment", "body": "input", "moment": 0} for k in range(3)}
    r = httpx.post(server.url + "/v1/solve", json={"document": document})
    assert r.status_code == 422 and error(r)["message"] == "/document/loads: 4 loads: the limit is 3"


# --- 2. strict reading -------------------------------------------------------------------
@pytest.mark.parametrize(
    "text, suffix, message",
    [
        ('{"bodies": {}, "bodies": {"a": {"position": [0, 0]}}}', ".json", "duplicate key 'bodies'"),
        ("bodies: {}\nbodies: {}\n", ".yaml", "duplicate key 'bodies'"),
        ("[" * 100_000, ".json", "nests deeper than 64 levels"),
        (b"\xff\xfe{}", ".json", "is not UTF-8 text"),
        ('{"bodies": {"a": {"position": [' + "1" * 5000 + ", 0]}}}", ".json", "is not valid JSON"),
    ],
)
def test_files_are_read_strictly(tmp_path, text, suffix, message):
    path = tmp_path / f"doc{suffix}"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(MechanismError) as info:
        load_document(path)
    assert message in info.value.problem


@pytest.mark.parametrize(
    "units, pointer, message",
    [
        ({"length": "uN/0"}, "/units/length", "'uN/0' is not a unit of length: expected a unit name, got '0'"),
        ({"force": "mm"}, "/units/force", "'mm' is not a unit of force (like N)"),
    ],
)
def test_a_bad_unit_is_blamed_on_itself(units, pointer, message):
    document = gripper()
    document["units"].update(units)
    with pytest.raises(MechanismError) as info:
        compile_mechanism(load_document(document))
    assert (info.value.pointer, info.value.problem) == (pointer, message)


def test_a_negative_radius_is_reported_in_the_document_unit():
    document = gripper()
    document["elements"]["a"]["radius"] = -0.2
    with pytest.raises(MechanismError, match=r"^/elements/a/radius: must be positive, got -0.2 mm$"):
        compile_mechanism(load_document(document))


# --- 5. field checks on design bounds --------------------------------------------------------
@pytest.mark.parametrize(
    "variable, pointer, message",
    [
        (
            {"path": "/sections/flexure/h", "lower": -1, "upper": 8},
            "/problem/design/0/lower",
            "must be positive, got -1 mm",
        ),
        (
            {"path": "/sections/flexure/h", "lower": 1, "upper": 8, "scale": 1e-320},
            "/problem/design/0/scale",
            "out of range",
        ),
        (
            {"path": "/elements/a/arc_angle", "lower": 10, "upper": 400},
            "/problem/design/0/upper",
            "arc angle must lie in (0, 360) deg",
        ),
    ],
)
def test_design_bounds_pass_the_field_checks(server, variable, pointer, message):
    problem = {"design": [variable], "objective": {"output": "end_effector.x"}}
    r = httpx.post(server.url + "/v1/optimize", json={"example": "gripper", "problem": problem})
    assert r.status_code == 422 and error(r)["pointer"] == pointer and message in error(r)["message"]


def test_nan_bounds_are_refused_at_post(server):
    body = (
        b'{"example": "gripper", "problem": {"design": [{"path": "/sections/flexure/h", "lower": NaN}], '
        b'"objective": {"output": "end_effector.x"}}}'
    )
    r = httpx.post(server.url + "/v1/optimize", content=body, headers={"Content-Type": "application/json"})
    assert r.status_code == 422 and error(r)["pointer"] == "/problem/design/0/lower"


# --- 7. security and transport -------------------------------------------------------------
@pytest.mark.parametrize("keys", [" , ,", " ", "\t", ","])
def test_api_keys_that_list_no_key_refuse_to_start(keys):
    from flexmech.api.cli import app

    result = CliRunner().invoke(app, ["serve"], env={"FLEXMECH_API_KEYS": keys, "NO_COLOR": "1"})
    assert result.exit_code == 2
    assert (
        "error: FLEXMECH_API_KEYS: Value error, lists no key, only blanks or commas (leave it empty to run "
        "without keys)"
    ) in result.stderr


def test_an_empty_key_list_runs_without_keys():
    from flexmech.service.settings import Settings

    assert Settings(api_keys="").api_keys == []


@pytest.mark.parametrize("media", ["Application/JSON", "APPLICATION/json; charset=utf-8", "application/vnd.api+JSON"])
def test_a_duplicate_key_is_refused_whatever_the_letter_case_of_the_media_type(server, media):
    body = b'{"example": "gripper", "overrides": {"/loads/actuation/force/1": 10}, "example": "gripper_nylon"}'
    r = httpx.post(server.url + "/v1/solve", content=body, headers={"Content-Type": media})
    assert r.status_code == 422 and error(r)["code"] == "duplicate_key"
    assert error(r)["message"] == "the body gives the key 'example' twice in one object"


def test_a_large_body_is_read_as_strictly_in_the_parser_process(server):
    """Bodies from api.body_parsing.LARGE_BODY bytes parse in their own process: the same
    answers as on the server's thread (a duplicate key, malformed JSON, too deep, a good body)."""
    from flexmech.api.body_parsing import LARGE_BODY

    pad = b'"' + b"x" * LARGE_BODY + b'"'
    cases = [
        (
            b'{"description": ' + pad + b', "example": "gripper", "example": "gripper_nylon"}',
            422,
            "duplicate_key",
            "the body gives the key 'example' twice in one object",
        ),
        (b'{"description": ' + pad + b', "example": "gripper",}', 400, "malformed_json", "the body is not valid JSON"),
        (
            b'{"description": ' + pad + b', "example": "gripper", "o": ' + b"[" * 100 + b"]" * 100 + b"}",
            400,
            "malformed_json",
            "the body nests deeper than 64 levels",
        ),
    ]
    for body, status, code, message in cases:
        assert len(body) >= LARGE_BODY
        r = httpx.post(server.url + "/v1/solve", content=body, headers={"Content-Type": "application/json"}, timeout=60)
        assert r.status_code == status and error(r)["code"] == code and error(r)["message"].startswith(message), r.text
    document = gripper()
    document["description"] = "x" * 20_000  # the longest a description may be; blanks make the body large
    body = json.dumps({"document": document}).encode() + b" " * LARGE_BODY
    r = httpx.post(server.url + "/v1/solve", content=body, headers={"Content-Type": "application/json"}, timeout=60)
    assert r.status_code == 200 and r.json()["status"] == "converged", r.text[:300]


def test_a_body_of_another_media_type_is_not_read_as_json():
    from flexmech.api.limits import is_json

    assert is_json(None) and is_json(b"application/json") and is_json(b" Application/Problem+JSON ;q=1")
    assert not is_json(b"text/plain") and not is_json(b"application/jsonp") and not is_json(b"multipart/form-data")


@pytest.mark.parametrize("path", ["/", "/jobs/0123", "/workbench/index.html", "/workbench/main.js"])
def test_the_page_and_its_files_carry_the_content_security_policy(server, path):
    r = httpx.get(server.url + path)
    assert r.status_code == 200, path
    assert "script-src 'self'" in r.headers["content-security-policy"]
    assert r.headers["x-content-type-options"] == "nosniff"


@pytest.mark.parametrize(
    "method, path, body",
    [
        ("GET", "/v1/health", None),
        ("GET", "/v1/examples", None),
        ("POST", "/v1/solve", b"{"),
        ("GET", "/v1/jobs/none", None),
        ("POST", "/v1/solve", b'{"example": "gripper"}'),
    ],
)
def test_every_answer_carries_nosniff(server, method, path, body):
    r = httpx.request(method, server.url + path, content=body, headers={"Content-Type": "application/json"})
    assert r.headers["x-content-type-options"] == "nosniff", (path, r.status_code)
    assert "content-security-policy" not in r.headers  # the page's policy is for the page and its files


def test_an_error_echoes_only_an_excerpt_of_a_long_name(server):
    name = "n" * 200  # the longest a name may be (its escaped pointer and colon: 232 characters)
    r = httpx.post(server.url + "/v1/solve", json={"example": "gripper", "overrides": {f"/elements/{name}/radius": 1}})
    assert r.status_code == 422
    assert len(r.content) < 2_000, len(r.content)
    assert re.search(r"nnnn\.\.\.\(232 characters\) not a numeric field", error(r)["message"])
    assert "n" * 101 not in r.text
    name = "n" * 100_000  # a pointer over its bound: its length said, the pointer not echoed
    r = httpx.post(server.url + "/v1/solve", json={"example": "gripper", "overrides": {f"/elements/{name}/radius": 1}})
    assert r.status_code == 422 and error(r)["pointer"] == "/overrides", r.text[:300]
    assert error(r)["message"] == "/overrides: a key of 100017 characters: keys here are at most 256 characters"


@pytest.mark.parametrize(
    "route, body",
    [
        ("/v1/solve", {"example": "rod_free_vibration", "analysis": "simulate"}),
        ("/v1/simulations", {"example": "rod_free_vibration"}),
        ("/v1/solve", {"example": "csfh", "analysis": "simulate", "simulate": {"scheme": "moreau"}}),
        ("/v1/simulations", {"example": "csfh", "simulate": {"scheme": "event_driven"}}),
    ],
)
def test_a_run_of_uncountably_many_steps_is_refused(server, route, body):
    body = {**body, "simulate": {**body.get("simulate", {}), "until": 1e300, "step": 1e-300}}
    r = httpx.post(server.url + route, json=body)
    assert r.status_code == 422, r.text
    assert error(r)["pointer"].endswith("/simulate/step")
    assert error(r)["message"] == "/simulate/step: 1e+300 s in steps of 1e-300 s would be more than 1e+12 steps"


def test_docs_are_served_from_the_package(server):
    page = httpx.get(server.url + "/docs")
    assert page.status_code == 200
    sources = re.findall(r'(?:src|href)="([^"]+)"', page.text)
    assert sources and all(s.startswith("/") for s in sources)  # nothing from a CDN
    for source in sources:
        assert httpx.get(server.url + source).status_code == 200, source
    assert httpx.get(server.url + "/openapi.json").status_code == 200  # public, as documented


def test_health_does_not_show_the_dask_address(dask_address):
    from flexmech.service.jobs.executors import DaskCluster

    cluster = DaskCluster(dask_address)
    try:
        host = dask_address.removeprefix("tcp://")
        assert cluster.description.startswith("Dask cluster (") and host not in cluster.description
    finally:
        cluster.close()


def test_names_cannot_break_json_pointers():
    document = gripper()
    document["materials"]["si/1~x"] = document["materials"].pop("silicon")
    with pytest.raises(MechanismError) as info:
        compile_mechanism(load_document(document))
    assert info.value.pointer == "/materials/si~11~0x"
    assert info.value.problem == "a name may not contain '/' or '~' (they are special in JSON pointers)"


# --- 9. messages a new user can act on ----------------------------------------------------
def test_a_document_posted_unwrapped_is_named_as_such(server):
    r = httpx.post(server.url + "/v1/solve", json=gripper())
    assert r.status_code == 422
    assert error(r)["message"].startswith('body: this is a mechanism document itself: send it as {"document": ')


def test_a_field_put_outside_its_group_is_told_where_it_belongs(server):
    """A trace's path given at the top level, and a target's value that is not a field: no
    request field suggests its own name back ("did you mean 'path'?")."""
    r = httpx.post(
        server.url + "/v1/solve", json={"example": "snap_through_arch", "analysis": "trace", "path": "/loads/P/force/1"}
    )
    assert r.status_code == 422 and error(r)["pointer"] == "/path"
    assert (
        error(r)["message"]
        == "/path: unknown field 'path' for the trace analysis (it belongs under trace: /trace/path)"
    )
    target = {"path": "/loads/actuation/force/1", "output": "end_effector.x", "equals": 0, "value": 3}
    r = httpx.post(server.url + "/v1/solve", json={"example": "gripper", "target": target})
    assert r.status_code == 422 and error(r)["pointer"] == "/target/value"
    assert "did you mean 'value'" not in error(r)["message"], error(r)["message"]


def test_a_misspelled_key_is_named(server):
    r = httpx.post(server.url + "/v1/solve", json={"exmaple": "gripper"})
    assert r.status_code == 422 and error(r)["pointer"] == "/exmaple"
    assert error(r)["message"].startswith("/exmaple: unknown field 'exmaple' (did you mean 'example'?)")
    document = gripper()
    document["elements"]["a"]["radious"] = document["elements"]["a"].pop("radius")
    with pytest.raises(MechanismError) as info:
        load_document(document)
    assert info.value.problem.startswith("unknown field 'radious' (did you mean 'radius'?)")
    document = gripper()
    document["sections"]["flexure"]["A"] = 1.0  # a field of a general section, not of a rectangle
    with pytest.raises(MechanismError) as info:
        load_document(document)
    assert (info.value.pointer, info.value.problem) == (
        "/sections/flexure/A",
        "unknown field 'A' (other kinds of object have it, this one does not)",
    )


def test_documents_read_from_files_keep_their_meaning(tmp_path):
    """A YAML copy of an example solves as the JSON does (the strict loader changes nothing else)."""
    import yaml

    path = tmp_path / "gripper.yaml"
    path.write_text(yaml.safe_dump(json.loads((EXAMPLES / "gripper.json").read_text())))
    assert load_document(path) == load_document(EXAMPLES / "gripper.json")
