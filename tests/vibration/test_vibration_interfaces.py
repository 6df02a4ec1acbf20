"""The vibration analyses through every interface: `flexmech modes` and `flexmech frf` (tables,
--json, figures: mode shapes, an animated mode, a Bode plot; bad flags named), /v1/solve over
real HTTP with its OpenAPI schemas, and the Python client's methods."""

from __future__ import annotations

import json

import httpx
import pytest
from conftest import EXAMPLES
from PIL import Image
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.api.client import Client

ENV = {"COLUMNS": "220", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "NO_COLOR": "1"}
ROD = str(EXAMPLES / "rod_free_vibration.json")
GRIPPER = str(EXAMPLES / "gripper_modes.json")


def invoke(*args: str):
    return CliRunner().invoke(app, list(args), env=ENV)


def test_flexmech_modes_prints_the_table_writes_the_report_and_draws_the_modes(tmp_path):
    result = invoke(
        "modes", ROD, "--count", "2", "--at", "undeformed", "--json", str(tmp_path / "rod.json"),
        "--plot", str(tmp_path / "modes.png"), "--animation", str(tmp_path / "mode1.gif"),
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "0.472213" in result.output and "frequency (Hz)" in result.output  # the period column, the table's head
    report = json.loads((tmp_path / "rod.json").read_text())
    assert report["modes"][0]["period"] == pytest.approx(0.47221, rel=2e-5)
    with Image.open(tmp_path / "modes.png") as figure:
        assert figure.size[0] > 600
    with Image.open(tmp_path / "mode1.gif") as movie:
        assert movie.n_frames == 40


def test_flexmech_frf_draws_a_bode_plot_and_names_bad_flags(tmp_path):
    common = ["frf", GRIPPER, "--input", "/loads/actuation/force/1", "--outputs", '["end_effector.x"]']
    result = invoke(*common, "--points", "200", "--plot", str(tmp_path / "bode.png"))
    assert result.exit_code == 0, result.output
    assert "resonances" in result.output and (tmp_path / "bode.png").stat().st_size > 10_000
    wrong = invoke(*common, "--plot", str(tmp_path / "bode.gif"))
    assert wrong.exit_code == 2 and "--plot: cannot tell the format of" in wrong.stderr
    empty = invoke(*common, "--start", "10", "--stop", "5")
    assert empty.exit_code == 2 and "--stop: Value error, the range is empty" in empty.stderr


def test_the_analyses_answer_over_http_and_through_the_client(api_server):
    schema = httpx.get(api_server.url + "/openapi.json").json()["components"]["schemas"]
    assert {"ModesSolve", "ModesResult", "FrequencyResponseSolve", "FrequencyResponseResult"} <= set(schema)
    body = {"example": "rod_free_vibration", "analysis": "modes", "count": 1, "at": "undeformed"}
    answer = httpx.post(api_server.url + "/v1/solve", json=body, timeout=120)
    assert answer.status_code == 200, answer.text
    assert answer.json()["modes"][0]["period"] == pytest.approx(0.47221, rel=2e-5)
    refused = httpx.post(api_server.url + "/v1/solve", json={**body, "count": 0}, timeout=60)
    assert refused.status_code == 422 and refused.json()["error"]["pointer"] == "/count"
    with Client(api_server.url) as client:
        report = client.analyze.frequency_response(
            example="gripper_modes",
            input="/loads/actuation/force/1",
            outputs=["end_effector.x"],
            points=50,
        )
        assert report.status == "converged"
        peaks = report.model_extra["resonances"]
        first = client.analyze.modes(example="gripper_modes", count=1, shapes=False)
        assert peaks[0]["frequency"] == pytest.approx(first.model_extra["modes"][0]["frequency"], rel=1e-3)


def test_the_state_space_answers_over_http_and_a_bad_output_is_a_422_naming_it(api_server):
    """The linearization analysis' state_space option (issue 29) on a carriage on a spring and a
    wheel on a torsion spring: their damped poles, the carriage's static gain 1/k."""
    from test_modes import body_on_springs

    doc = body_on_springs(0.3, 0.002, 1200.0, 4.5)
    doc["loads"] = {"push": {"type": "force", "body": "carriage", "force": [0, 0]}}
    asked = {"inputs": ["/loads/push/force/0"], "outputs": ["bodies.carriage.x"], "damping_ratio": 0.1}
    body = {"document": doc, "analysis": "linearization", "at": "undeformed", "state_space": asked}
    answer = httpx.post(api_server.url + "/v1/solve", json=body, timeout=60)
    assert answer.status_code == 200, answer.text
    space = answer.json()["state_space"]
    assert space["static_gain"] == [[pytest.approx(1 / 1200.0, rel=1e-12)]] and space["units"]["inputs"] == ["N"]
    omegas = ((1200.0 / 0.3) ** 0.5, (4.5 / 0.002) ** 0.5)  # the carriage's and the wheel's
    assert sorted(space["poles"]["real"]) == pytest.approx(sorted(-0.1 * w for w in omegas * 2), rel=1e-12)
    wrong = {**body, "state_space": {**asked, "outputs": ["bodies.carriage.q"]}}
    refused = httpx.post(api_server.url + "/v1/solve", json=wrong, timeout=60)
    assert refused.status_code == 422 and refused.json()["error"]["pointer"] == "/state_space/outputs/0"


def test_flexmech_batch_runs_the_modes_of_a_folder(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("rod_free_vibration.json", "csfh.json"):
        (folder / name).write_text((EXAMPLES / name).read_text())
    options = json.dumps({"count": 2, "at": "undeformed", "shapes": False})
    result = invoke("batch", str(folder), "--out", str(tmp_path / "out"), "--analysis", "modes", "--options", options)
    assert result.exit_code == 0, result.output
    rod = json.loads((tmp_path / "out" / "rod_free_vibration.json").read_text())
    assert rod["analysis"] == "modes" and rod["modes"][0]["period"] == pytest.approx(0.47221, rel=2e-5)
    hinge = json.loads((tmp_path / "out" / "csfh.json").read_text())
    assert hinge["coordinates"] == "bodies" and hinge["modes"][0]["kind"] == "elastic"  # seed 004's body mass
