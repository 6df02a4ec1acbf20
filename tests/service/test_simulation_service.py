"""The simulation job over real HTTP (uvicorn): POST /v1/simulations stores the run per time
window; its result equals the same run answered by /v1/solve with analysis "simulate"; a
server killed in the middle resumes from the last stored window, and the windows stored
before the kill come back untouched; bad fields are 422 naming them."""

from __future__ import annotations

import time

import httpx
import numpy as np

from flexmech.api.client import Client
from flexmech.service.dynamics.stepping import WINDOW


def _wait_until(condition, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return
        time.sleep(0.02)
    raise AssertionError(f"timed out waiting for {what}")


def solved_in_one(server, example: str, simulate: dict) -> dict:
    r = httpx.post(
        f"{server.url}/v1/solve", json={"example": example, "analysis": "simulate", "simulate": simulate}, timeout=300
    )
    assert r.status_code == 200, r.text
    return r.json()


def test_a_simulation_job_equals_the_simulate_analysis(api_server):
    simulate = {"until": 3.0, "step": 0.01, "every": 2}
    with Client(api_server.url) as client:
        job = client.simulation(example="spinning_rod_case1", simulate=simulate)
        windows = -(-300 // WINDOW)  # 300 steps, stored per stepping window
        assert job.kind == "simulation" and job.progress.total == windows
        final = client.wait(job.id, timeout=300)
        assert final.status == "succeeded", final.error
        result = client.result(job.id).result
    one = solved_in_one(api_server, "spinning_rod_case1", simulate)
    assert one["status"] == "finished" and result["status"] == "finished"
    assert result["times"] == one["times"] and len(one["times"]) == 151
    for name, values in one["outputs"].items():
        np.testing.assert_allclose(result["outputs"][name], values, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(result["energies"]["input_work"], one["energies"]["input_work"], rtol=1e-10)
    assert abs(result["energy_balance_error"] - one["energy_balance_error"]) < 1e-9
    assert result["units"]["length"] == "m" and result["windows_stored"] == windows


def test_bad_simulation_fields_are_422_naming_them(api_server):
    for simulate, pointer, words in [
        ({"step": -0.01}, "/simulate/step", "greater than 0"),
        (
            {"until": 1.0, "histories": {"/loads/spin/rotation": "open('x')"}},
            "/simulate/histories/loads~1spin~1rotation",
            "a call of 'open' is not allowed",
        ),
        ({"until": 1e3, "step": 1e-6}, "/simulate/step", "over the limit of 1000000"),
        ({"until": 1e9, "step": 1e-6}, "/simulate/step", "1e+09 s in steps of 1e-06 s would be more than 1e+12 steps"),
    ]:
        r = httpx.post(f"{api_server.url}/v1/simulations", json={"example": "spinning_rod_case1", "simulate": simulate})
        assert r.status_code == 422, r.text
        error = r.json()["error"]
        assert error["pointer"] == pointer and words in error["message"], error


def test_a_simulation_job_carries_a_located_contact_onset_across_its_windows(api_server):
    """The dynamic grasp (a Lankarani-Nikravesh pair): the job's stored windows carry the onset
    located in one of them (its approach speed, the step it added) to the next, and the job's
    contact force follows the one-call run's (to the Newton tolerance: after the onset the two
    cut their windows of steps in other places)."""
    simulate = {"until": 0.005, "every": 1}
    with Client(api_server.url) as client:
        job = client.simulation(example="gripper_grasp_dynamics", simulate=simulate)
        final = client.wait(job.id, timeout=300)
        assert final.status == "succeeded", final.error
        result = client.result(job.id).result
    one = solved_in_one(api_server, "gripper_grasp_dynamics", simulate)
    assert result["windows_stored"] > 5 and len(result["times"]) == len(one["times"])
    np.testing.assert_allclose(result["times"], one["times"], rtol=1e-9)  # the onset's time to round-off
    indentation = np.array(result["outputs"]["contacts.grip.indentation"])
    assert np.abs(indentation).min() < 1e-12  # the onset's own state, stored by its window
    force = np.array(one["outputs"]["contacts.grip.normal_force"])
    np.testing.assert_allclose(
        result["outputs"]["contacts.grip.normal_force"], force, rtol=1e-6, atol=1e-9 * force.max()
    )


def test_a_simulation_job_refuses_a_contact_law_link_dynamics_does_not_take(api_server):
    import json
    from pathlib import Path

    doc = json.loads((Path(__file__).resolve().parents[2] / "examples" / "gripper_grasp_dynamics.json").read_text())
    doc["contacts"]["pairs"]["grip"]["friction"] = 0.3  # Coulomb's coefficient
    r = httpx.post(f"{api_server.url}/v1/simulations", json={"document": doc})
    assert r.status_code == 422, r.text
    error = r.json()["error"]
    assert error["pointer"] == "/document/contacts/pairs/grip/friction"
    assert "not Coulomb's coefficient" in error["message"]


def test_a_killed_server_resumes_the_simulation_from_its_last_window(deployment):
    """SIGKILL mid-run (the four-bar, 0.2 s in 1000 steps, stored in 50 windows of 20); a new
    server on the same store finishes it. The windows stored before come back as they were, and
    the whole run equals an uninterrupted one (to rounding: that one runs in another process)."""
    simulate = {"until": 0.2, "step": 0.0002, "every": 20, "adaptive": False}
    server = deployment.start(FLEXMECH_CHUNK_SIZE="1")
    with Client(server.url) as client:
        job = client.simulation(example="four_bar_dynamics", simulate=simulate)
        assert job.progress.total == 50
        _wait_until(lambda: client.job(job.id).progress.done >= 3, 240, "three windows")
        before = client.result(job.id)
        server.kill()
    assert not before.complete and 3 <= before.result["windows_stored"] < 50
    server = deployment.start()
    try:
        with Client(server.url) as client:
            final = client.wait(job.id, timeout=300)
            after = client.result(job.id)
            one = solved_in_one(server, "four_bar_dynamics", simulate)
    finally:
        server.stop()
    assert final.status == "succeeded" and final.restarts == 1
    kept = len(before.result["times"])
    assert after.result["times"][:kept] == before.result["times"]
    assert after.result["outputs"]["C.x"][:kept] == before.result["outputs"]["C.x"]
    assert after.result["times"] == one["times"]
    # the one-call run goes through the server's own process (its BLAS threads sum in another order)
    np.testing.assert_allclose(after.result["outputs"]["C.y"], one["outputs"]["C.y"], rtol=1e-12)
    np.testing.assert_allclose(after.result["energies"]["input_work"], one["energies"]["input_work"], rtol=1e-10)


def test_a_simulation_job_refuses_an_accuracy_target_and_says_where_it_runs(api_server):
    simulate = {"accuracy": 1e-3, "outputs": ["bodies.tip.x"]}
    r = httpx.post(f"{api_server.url}/v1/simulations", json={"example": "rod_free_vibration", "simulate": simulate})
    assert r.status_code == 422, r.text
    error = r.json()["error"]
    assert error["pointer"] == "/simulate/accuracy"
    assert "/v1/solve (analysis simulate)" in error["message"]
