"""The HTTP API over real HTTP: a uvicorn process on loopback, called through api.client."""

from __future__ import annotations

import asyncio
import json

import httpx
import numpy as np
import pytest
from conftest import ACTUATION, EXAMPLES, Deployment

from flexmech.api.client import AsyncClient, Client, FlexmechError
from flexmech.models import compile_mechanism, load_document
from flexmech.service import inverse_wrenches, solve_equilibrium, solve_for_target, tangent_stiffness

CLOSING = {"path": ACTUATION, "output": "end_effector.x", "equals": 0.0}


@pytest.fixture(scope="module")
def client(api_server):
    with Client(api_server.url) as c:
        yield c


@pytest.mark.parametrize("model, paper", [("linear", 63.95), ("partial_nonlinear", 77.04)])
def test_closing_force_over_http_equals_the_core(client, model, paper):
    answer = client.solve(example="gripper", model=model, target=CLOSING)
    mech = compile_mechanism(load_document(EXAMPLES / "gripper.json"), model=model)
    core = solve_for_target(mech, ACTUATION, "end_effector.x", 0.0)
    assert answer.status == "converged" and answer.target.status == "converged"
    assert answer.target.unit == "uN"
    assert answer.target.value == pytest.approx(core.value, rel=1e-9)
    assert answer.target.value == pytest.approx(paper, abs=0.05)
    assert answer.outputs["end_effector.x"] == pytest.approx(0.0, abs=1e-9)


def test_equilibrium_outputs_and_stiffness_equal_the_core(client, gripper_dict):
    answer = client.solve(document=gripper_dict, overrides={ACTUATION: 50}, stiffness=True)
    mech = compile_mechanism(load_document(gripper_dict)).with_values({ACTUATION: 50})
    core = solve_equilibrium(mech)
    for name, value in core.outputs().items():
        assert answer.outputs[name] == pytest.approx(value, rel=1e-12, abs=1e-12)
    assert answer.output_units["end_effector.x"] == "mm"
    assert answer.warnings and "20 deg" in answer.warnings[0]  # flexure d beyond the models' range
    K = tangent_stiffness(mech, core.z).K
    np.testing.assert_allclose(np.array(answer.stiffness.K), K, rtol=1e-12)


def test_inverse_and_linearization(client, gripper_dict):
    mech = compile_mechanism(load_document(gripper_dict))
    answer = client.solve(document=gripper_dict, analysis="inverse", displacements={"input": [0.01, 0.002, 0.5]})
    core = inverse_wrenches(mech, {"input": (0.01, 0.002, 0.5)})
    assert answer.wrenches["input"].Fx == pytest.approx(core["input"][0], rel=1e-12)
    assert answer.wrenches["input"].M == pytest.approx(core["input"][2], rel=1e-12)
    assert answer.wrench_units == {"Fx": "uN", "Fy": "uN", "M": "uN*mm"}
    lin = client.solve(document=gripper_dict, analysis="linearization", at="undeformed")
    np.testing.assert_allclose(np.array(lin.stiffness.K), tangent_stiffness(mech).K, rtol=1e-12)
    assert lin.stiffness.symmetric


def test_non_convergence_is_a_result(client):
    answer = client.solve(example="gripper", overrides={ACTUATION: 400}, options={"max_iterations": 3})
    assert answer.status == "not_converged"
    assert answer.iterations == 3 and "no convergence in 3 iterations" in answer.message
    assert answer.residual_norm > 0


def test_async_client_and_examples(api_server):
    async def main():
        async with AsyncClient(api_server.url) as c:
            names = [e.name for e in await c.examples()]
            doc = await c.example("gripper_nylon")
            answer = await c.solve(document=doc, target=CLOSING)
            health = await c.health()
            return names, answer, health

    names, answer, health = asyncio.run(main())
    assert {"gripper", "gripper_nylon", "gripper_si"} <= set(names)
    assert answer.target.value == pytest.approx(77.0346 / (100 / 3.84), rel=1e-4)
    assert health.database == "sqlite" and "process pool" in health.executor


# --- bad input: one error shape, the field named --------------------------------------------
def _error(response: httpx.Response) -> dict:
    body = response.json()
    keys = set(body["error"]) - {"problems"}  # every field's problem, when several have one
    assert set(body) == {"error"} and keys == {"status", "code", "message", "pointer"}
    assert body["error"]["status"] == response.status_code
    return body["error"]


def test_malformed_json_is_400(api_server):
    r = httpx.post(
        api_server.url + "/v1/solve", content=b'{"example": "gripper",', headers={"Content-Type": "application/json"}
    )
    error = _error(r)
    assert r.status_code == 400 and error["code"] == "malformed_json"
    assert error["message"].startswith("the body is not valid JSON")


def test_schema_violation_is_422_with_the_pointer(client):
    with pytest.raises(FlexmechError) as info:
        client.solve(SolveRequestUnchecked(example="gripper", options={"max_iterations": "many"}))
    assert info.value.status == 422 and info.value.code == "invalid_request"
    assert info.value.pointer == "/options/max_iterations"
    assert "valid integer" in info.value.message


def test_document_error_is_422_with_the_pointer_into_the_document(client, gripper_dict):
    doc = json.loads(json.dumps(gripper_dict))
    doc["elements"]["c"]["to"] = "folower"
    with pytest.raises(FlexmechError) as info:
        client.solve(document=doc)
    assert info.value.status == 422 and info.value.code == "invalid_input"
    assert info.value.pointer == "/document/elements/c/to"
    assert "unknown body 'folower'" in info.value.message


def test_unknown_job_is_404(client):
    with pytest.raises(FlexmechError) as info:
        client.job("0123456789abcdef0123456789abcdef")
    assert info.value.status == 404 and info.value.message == "no job '0123456789abcdef0123456789abcdef'"


def test_body_over_the_size_limit_is_413(api_server, gripper_dict):
    big = {"document": gripper_dict, "overrides": {f"/pad/{k}": 1.0 for k in range(20000)}}
    r = httpx.post(api_server.url + "/v1/solve", json=big)
    error = _error(r)
    assert r.status_code == 413 and error["code"] == "body_too_large"
    assert "over the limit of 200000 bytes" in error["message"]


def test_chunked_body_over_the_size_limit_is_413(api_server):
    def chunks():  # no Content-Length: the server counts as it reads
        yield b'{"example": "gripper", "overrides": {'
        for k in range(30000):
            yield f'"/pad/{k}": 1.0, '.encode()
        yield b'"/pad/x": 1}}'

    r = httpx.post(api_server.url + "/v1/solve", content=chunks(), headers={"Content-Type": "application/json"})
    assert r.status_code == 413 and _error(r)["code"] == "body_too_large"


def test_too_many_sweep_points_is_422(client):
    with pytest.raises(FlexmechError) as info:
        client.sweep(
            example="gripper",
            parameters=[
                {"path": ACTUATION, "start": 0, "stop": 10, "steps": 40},
                {"path": "/sections/flexure/h", "values": [0.004, 0.0045, 0.005, 0.0055, 0.006]},
                {"path": "/sections/flexure/b", "values": [0.02, 0.025, 0.03, 0.035, 0.04]},
            ],
        )
    assert info.value.status == 422 and info.value.pointer == "/parameters"
    assert info.value.message == "/parameters: 1025 sweep points: the limit is 1000"


def test_unknown_route_and_example_have_the_same_shape(api_server):
    r = httpx.get(api_server.url + "/v1/nothing")
    assert r.status_code == 404 and _error(r)["code"] == "not_found"
    r = httpx.get(api_server.url + "/v1/examples/unknown")
    assert r.status_code == 404 and "no example 'unknown'" in _error(r)["message"]


def test_openapi_operation_ids_are_stable(api_server):
    spec = httpx.get(api_server.url + "/openapi.json").json()
    ids = {op["operationId"] for path in spec["paths"].values() for op in path.values()}
    assert ids == {
        "solve",
        "create_sweep",
        "create_optimization",
        "create_contact_path",
        "create_simulation",
        "create_impact_study",
        "create_export",
        "create_analysis_job",
        "draw",
        "draw_for_fabrication",
        "parse_document",
        "upgrade_document",
        "list_jobs",
        "get_job",
        "get_job_result",
        "get_job_request",
        "get_job_archive",
        "cancel_job",
        "delete_job",
        "get_usage",
        "list_examples",
        "get_example",
        "health",
        "list_analyses",
        "list_job_kinds",
    }


# --- API keys -------------------------------------------------------------------------------
KEY_A, KEY_B = "alpha-key-0123456789", "bravo-key-0123456789"


@pytest.fixture(scope="module")
def keyed_server(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("keyed")
    server = Deployment(
        "sqlite",
        {
            "FLEXMECH_DATA_DIR": str(tmp / "data"),
            "FLEXMECH_WORKERS": "1",
            "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
            "FLEXMECH_API_KEYS": f"{KEY_A},{KEY_B}",
        },
        tmp,
    ).start()
    yield server
    server.stop()


def test_missing_or_wrong_key_is_401(keyed_server):
    for headers, message in (
        ({}, "missing API key: send it in the X-API-Key header"),
        ({"X-API-Key": "not-a-key-of-this-server"}, "API key not recognized"),
    ):
        r = httpx.post(keyed_server.url + "/v1/solve", json={"example": "gripper"}, headers=headers)
        assert r.status_code == 401 and _error(r)["message"] == message
    assert httpx.get(keyed_server.url + "/v1/health").status_code == 200  # health needs no key


def test_a_job_is_visible_only_to_its_key(keyed_server):
    with Client(keyed_server.url, api_key=KEY_A) as a, Client(keyed_server.url, api_key=KEY_B) as b:
        job = a.sweep(example="gripper", parameters=[{"path": ACTUATION, "values": [0, 10, 20]}])
        assert a.wait(job.id, timeout=60).status == "succeeded"
        for call in (b.job, b.result, b.cancel):
            with pytest.raises(FlexmechError) as info:
                call(job.id)
            assert info.value.status == 404 and info.value.message == f"no job '{job.id}'"
        assert len(a.result(job.id).result.points) == 3


class SolveRequestUnchecked:
    """A request the client sends as it is, to see the server's own validation."""

    def __init__(self, **fields):
        self.fields = fields

    def model_dump(self, **_):
        return self.fields


# --- limits on work -------------------------------------------------------------------------
@pytest.fixture(scope="module")
def tight_server(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("tight")
    server = Deployment(
        "sqlite",
        {
            "FLEXMECH_DATA_DIR": str(tmp / "data"),
            "FLEXMECH_WORKERS": "1",
            "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
            "FLEXMECH_API_KEYS": "",
            "FLEXMECH_SOLVE_TIME_LIMIT": "1e-6",
            "FLEXMECH_JOB_TIME_LIMIT": "1",
            "FLEXMECH_CHUNK_SIZE": "1",
            "FLEXMECH_MAX_ELEMENTS": "3",
        },
        tmp,
    ).start()
    yield server
    server.stop()


def test_solve_time_limit_stops_newton_with_a_status(tight_server, gripper_dict):
    small = json.loads(json.dumps(gripper_dict))
    del small["elements"]["d"]  # 3 elements: within this server's element limit
    small["bodies"]["follower"]["fixed"] = True
    with Client(tight_server.url) as c:
        answer = c.solve(document=small, options={"time_limit": 60})  # the server's limit wins
    assert answer.status == "time_limit"
    assert answer.message == "stopped by the time limit of 1e-06 s"


def test_element_limit_is_422(tight_server):
    with Client(tight_server.url) as c, pytest.raises(FlexmechError) as info:
        c.solve(example="gripper")
    assert info.value.status == 422 and info.value.pointer == "/document/elements"
    assert info.value.message == "/document/elements: 4 elements: the limit is 3"


def test_job_time_limit_fails_the_job_and_keeps_its_points(tight_server, gripper_dict):
    small = json.loads(json.dumps(gripper_dict))
    del small["elements"]["d"]
    small["bodies"]["follower"]["fixed"] = True
    with Client(tight_server.url) as c:
        job = c.sweep(
            document=small,
            parameters=[{"path": ACTUATION, "start": 0, "stop": 50, "steps": 19_999}],
            continuation=ACTUATION,
            outputs=["end_effector.x"],
        )
        final = c.wait(job.id, timeout=60)
        stored = c.result(job.id)
    assert final.status == "failed"
    assert final.error.startswith("stopped by the job time limit of 1 s; ")
    assert f"{len(stored.result.points)} of 20000 points are stored" in final.error
    assert not stored.complete
