"""The vibration analyses through every interface: `flexmech modes` and `flexmech frf` (tables,
--json, figures: mode shapes, an animated mode, a Bode plot; bad flags named), /v1/solve over
real HTTP with its OpenAPI schemas, and the Python client's methods."""

from __future__ import annotations

import json
import re

import httpx
import numpy as np
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


# --- issue 49: every mode drawn with its bodies; every mode in range in the resonance table ---
@pytest.fixture(scope="module")
def gripper_modes(tmp_path_factory) -> tuple[dict, str]:
    """`flexmech modes gripper_modes --count 10 --plot`: its report (--json) and its output."""
    folder = tmp_path_factory.mktemp("modes")
    result = invoke(
        "modes", GRIPPER, "--count", "10", "--json", str(folder / "modes.json"), "--plot", str(folder / "modes.png")
    )
    assert result.exit_code == 0, result.output
    assert (folder / "modes.png").stat().st_size > 10_000
    return json.loads((folder / "modes.json").read_text()), result.output


def _points_of(ax) -> list[np.ndarray]:
    """Each drawn line's points (2 x n)."""
    return [np.vstack(line.get_data()).astype(float) for line in ax.get_lines()]


def test_every_requested_mode_is_drawn_with_its_bodies_and_the_scale_said(gripper_modes):
    """Ten modes asked, ten panels (the figure once stopped at six), each titled with its mode's
    frequency; each body moved by the mode as its elements are: its reference point drawn where
    the state has it and where the mode moves it, joined to the moved ends of the elements it
    carries (the rigid links); the shapes' scale stated in the document's length unit."""
    from flexmech.service.vibration.figures import SHOWN, Drawn, modes_figure

    report, _ = gripper_modes
    fig = modes_figure(report, "mm")
    axes = fig.get_axes()
    assert len(report["modes"]) == 10 and len(axes) == 10
    for ax, mode in zip(axes, report["modes"]):
        assert ax.get_title() == f"mode {mode['mode']}: {mode['frequency']:.5g} Hz"
        lines = _points_of(ax)
        drawn = Drawn(report, mode)
        moved_lines = drawn.lines(1.0)
        for name, body in report["bodies"].items():
            state = np.array(body["reference"])
            moved = state + drawn.scale * np.array(mode["shape"]["bodies"].get(name, [0.0, 0.0])[:2])
            assert any(np.allclose(p[:, 0], state) for p in lines)  # drawn at the state
            for element, end in body["ends"]:
                tip = moved_lines[element][:, 0 if end == "start" else -1]
                link = np.column_stack([moved, tip])
                assert any(p.shape == (2, 2) and np.allclose(p, link) for p in lines), (mode["mode"], name, element)
        most = max(np.hypot(*(moved_lines[n] - np.array(report["lines"][n]).T)).max() for n in report["lines"])
        assert most <= SHOWN * drawn.size * (1 + 1e-9)  # no point moves farther than the stated motion
    title = fig._suptitle.get_text()
    assert f"{SHOWN:.0%} of the mechanism's size" in title and f"{SHOWN * drawn.size:.3g} mm" in title
    assert "10 modes" in title


def test_the_resonance_table_lists_every_mode_in_the_range_with_units(gripper_modes, tmp_path):
    """`flexmech frf` on the gripper: every elastic mode the frequency range holds (by the modes
    analysis' frequencies) is a row of the resonance table, mode 2 (7077 Hz, beside mode 3's
    larger peak at 7401 Hz) included; the heads carry the units: Hz, the output's unit per the
    input's, degrees."""
    modes, _ = gripper_modes
    out = tmp_path / "frf.json"
    result = invoke(
        "frf", GRIPPER, "--input", "/loads/actuation/force/1", "--output", "end_effector.x", "--json", str(out)
    )
    assert result.exit_code == 0, result.output
    report = json.loads(out.read_text())
    start, stop = report["frequencies"][0], report["frequencies"][-1]
    in_range = {m["mode"] for m in modes["modes"] if m["frequency"] is not None and start <= m["frequency"] <= stop}
    assert {1, 2, 3} <= in_range and max(in_range) < 10  # the range holds mode 2, and not every mode asked
    head = next(line for line in result.output.splitlines() if "┃" in line and "frequency" in line)
    hertz = re.search(r"frequency \((k?Hz)\)", head)  # Hz, or kHz when the largest is above 1e4 Hz
    assert hertz is not None, head
    for unit_head in ("amplitude (mm/uN)", "phase (deg)", f"bandwidth ({hertz[1]})"):
        assert unit_head in head
    per_hertz = 1e3 if hertz[1] == "kHz" else 1.0
    rows = [line.split("│")[1:-1] for line in result.output.splitlines() if line.count("│") == 8]
    listed = {int(row[0]) for row in rows}
    assert listed == in_range
    assert {peak["mode"] for peak in report["resonances"]} == in_range
    second = next(row for row in rows if int(row[0]) == 2)
    assert abs(float(second[2]) * per_hertz / modes["modes"][1]["frequency"] - 1) < 0.01  # near its natural frequency


def test_a_list_option_is_a_repeated_flag_and_its_json_form_still_works(tmp_path):
    """--output A --output B watches both, as --outputs '["A", "B"]' did (and still does)."""
    common = ["frf", GRIPPER, "--input", "/loads/actuation/force/1", "--points", "20"]
    repeated, old = tmp_path / "repeated.json", tmp_path / "old.json"
    first = invoke(*common, "--output", "end_effector.x", "--output", "end_effector.y", "--json", str(repeated))
    second = invoke(*common, "--outputs", '["end_effector.x", "end_effector.y"]', "--json", str(old))
    assert first.exit_code == second.exit_code == 0, first.output + second.output
    one, other = (json.loads(path.read_text()) for path in (repeated, old))
    assert list(one["responses"]) == list(other["responses"]) == ["end_effector.x", "end_effector.y"]
    assert one["responses"] == other["responses"]
    wrong = invoke(*common, "--output", "end_effector.x", "--output", "bodies.nope")
    assert wrong.exit_code == 2 and "--output bodies.nope: no output 'bodies.nope'" in wrong.stderr
    none = invoke(*common)
    assert none.exit_code == 2 and "--output: Field required" in none.stderr
