"""The trace analysis of /v1/solve over real HTTP (a uvicorn process on loopback): arc-length
continuation through the snap-through of the shallow clamped arch, checked against
service.solvers.continuation.trace_path, against the slope of its own load-displacement points,
and against natural continuation with bisection (tests/continuation_oracles.py)."""

from __future__ import annotations

import json

import httpx
import numpy as np
import pytest
from conftest import EXAMPLES
from continuation_oracles import natural_limit
from typer.testing import CliRunner

from flexmech.models import compile_mechanism, load_document
from flexmech.service.solvers.continuation import trace_path

LOAD, STOP = "/loads/P/force/1", -300.0
ARCH = EXAMPLES / "snap_through_arch.json"
ENV = {"COLUMNS": "200", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "NO_COLOR": "1"}
# The extremum of a parabola through the three points around a sampled limit point: its
# relative error in the limit load at a first step of 5 N and of 2 N (measured 3e-5 and 1.3e-4
# at 5 N, 4e-6 and 8e-6 at 2 N: it falls about as the cube of the spacing).
SLOPE_TOLERANCE = {5.0: 5e-4, 2.0: 5e-5}


def post(server, body: dict) -> httpx.Response:
    return httpx.post(server.url + "/v1/solve", json=body, timeout=120)


def traced(server, step: float, **fields) -> dict:
    r = post(
        server,
        {
            "example": "snap_through_arch",
            "analysis": "trace",
            "trace": {"path": LOAD, "stop": STOP, "step": step, **fields},
        },
    )
    assert r.status_code == 200, r.text
    return r.json()


@pytest.fixture(scope="module")
def arch():
    return compile_mechanism(load_document(ARCH))


@pytest.fixture(scope="module")
def answers(api_server) -> dict[float, dict]:
    return {step: traced(api_server, step) for step in SLOPE_TOLERANCE}


def test_the_trace_over_http_is_trace_path(arch, answers):
    answer, core = answers[5.0], trace_path(arch, LOAD, STOP, 5.0)
    assert answer["analysis"] == "trace" and answer["status"] == "converged"
    assert answer["path_status"] == "completed" and core.status == "completed"
    assert answer["path"] == LOAD and answer["unit"] == "N" and answer["source"] == "request"
    assert [lp["kind"] for lp in answer["limit_points"]] == ["minimum", "maximum"]
    for lp, expected in zip(answer["limit_points"], core.limit_points, strict=True):
        assert lp["value"] == pytest.approx(expected.value, rel=1e-9)
        assert lp["after_point"] == expected.after_point
    np.testing.assert_allclose(answer["values"], [p.value for p in core.points], rtol=1e-9)
    assert answer["values"][0] == 0.0 and answer["values"][-1] == pytest.approx(STOP, rel=1e-12)
    # The columns are the points' numbers, in the document's units.
    assert answer["outputs"]["crown.dy"] == [p["outputs"]["crown.dy"] for p in answer["points"]]
    assert answer["output_units"]["crown.dy"] == "mm"
    assert [p["value"] for p in answer["points"]] == answer["values"]


@pytest.mark.parametrize("step", sorted(SLOPE_TOLERANCE))
def test_limit_loads_are_where_the_load_displacement_slope_changes_sign(answers, step):
    """From the returned points only: the load P against the crown's deflection dy has an
    extremum at each limit point, and the least eigenvalue of the body stiffness changes
    sign there (the stability flag flips)."""
    answer = answers[step]
    P, dy = np.array(answer["values"]), np.array(answer["outputs"]["crown.dy"])
    assert np.all(np.diff(dy) < 0)  # dy parametrizes the path
    slope = np.diff(P) / np.diff(dy)
    flips = [i for i in range(len(slope) - 1) if slope[i] * slope[i + 1] < 0]
    assert len(flips) == 2
    for lp, flip in zip(answer["limit_points"], flips, strict=True):
        k = flip + 1  # the sampled extremum
        a, b, c = np.polyfit(dy[k - 1 : k + 2], P[k - 1 : k + 2], 2)
        assert c - b * b / (4 * a) == pytest.approx(lp["value"], rel=SLOPE_TOLERANCE[step])
        before, after = answer["points"][lp["after_point"]], answer["points"][lp["after_point"] + 1]
        assert before["stable"] != after["stable"]
        assert before["eigenvalues"][0] * after["eigenvalues"][0] < 0
    assert [p["stable"] for p in answer["points"]].count(False) == answer["limit_points"][1]["after_point"] - answer[
        "limit_points"
    ][0]["after_point"]


def test_the_first_limit_load_is_where_natural_continuation_ends(arch, answers):
    loading = natural_limit(arch, LOAD, 0.0, -10.0, rel_tol=1e-9)
    assert answers[2.0]["limit_points"][0]["value"] == pytest.approx(loading, rel=1e-6)
    assert -104 < loading < -101  # the example's description: "about -102 N"


def test_a_path_cut_short_is_a_status_not_an_error(api_server):
    answer = traced(api_server, 5.0, max_points=5)
    assert answer["status"] == "not_converged" and answer["path_status"] == "max_points"
    assert answer["message"].startswith("stopped after 5 points at ") and len(answer["values"]) == 5


def test_the_time_limit_stops_a_path_with_its_points_so_far(api_server):
    r = post(
        api_server,
        {
            "example": "snap_through_arch",
            "analysis": "trace",
            "options": {"time_limit": 0.5},
            "trace": {"path": LOAD, "stop": STOP, "step": 1e-4, "max_points": 4000},  # its report fits an answer
        },
    )
    answer = r.json()
    assert r.status_code == 200 and answer["status"] == "time_limit" and answer["path_status"] == "stopped"
    assert answer["message"].startswith("stopped after ") and 1 <= len(answer["values"]) < 4000
    assert answer["values"][-1] > -1.0  # 1e-4 N steps: nowhere near the stop in half a second


def test_without_trace_the_sweep_section_is_followed(api_server, answers):
    doc = json.loads(ARCH.read_text())
    r = post(api_server, {"document": doc, "analysis": "trace"})
    assert r.status_code == 422
    error = r.json()["error"]
    assert error["pointer"] == "/trace" and "give trace {path, stop, step}" in error["message"]
    doc["sweep"] = {"path": LOAD, "start": 0, "stop": STOP, "steps": 60}  # 5 N steps
    answer = post(api_server, {"document": doc, "analysis": "trace"}).json()
    assert answer["source"] == "sweep" and answer["step"] == 5.0
    assert answer["values"] == answers[5.0]["values"]


@pytest.mark.parametrize(
    "trace, pointer, message",
    [
        (
            {"path": "/loads/P/force/7", "stop": STOP, "step": 5},
            "/trace/path",
            "/trace/path: not a numeric field of this mechanism",
        ),
        ({"path": "loads/P/force/1", "stop": STOP, "step": 5}, "/trace/path", "/trace/path: "),
        ({"path": LOAD, "stop": STOP, "step": 0}, "/trace/step", "/trace/step: "),
        ({"path": LOAD, "stop": 0, "step": 5}, "/trace/stop", "/trace/stop: the path starts at 0 N"),
    ],
)
def test_bad_trace_fields_are_422_naming_the_field(api_server, trace, pointer, message):
    r = post(api_server, {"example": "snap_through_arch", "analysis": "trace", "trace": trace})
    assert r.status_code == 422
    error = r.json()["error"]
    assert error["pointer"] == pointer and error["message"].startswith(message)


def test_the_cli_solve_command_runs_the_trace(tmp_path):
    from flexmech.api.cli import app

    failed = CliRunner().invoke(app, ["solve", str(ARCH), "--analysis", "trace"], env=ENV)
    assert failed.exit_code == 2 and "Traceback" not in failed.output
    assert failed.stderr.startswith("error: /trace: the document has no sweep section")
    doc = json.loads(ARCH.read_text())
    doc["sweep"] = {"path": LOAD, "start": 0, "stop": STOP, "steps": 15}
    path = tmp_path / "arch.json"
    path.write_text(json.dumps(doc))
    result = CliRunner().invoke(
        app, ["solve", str(path), "--analysis", "trace", "--json", str(tmp_path / "t.json")], env=ENV
    )
    assert result.exit_code == 0, result.output
    report = json.loads((tmp_path / "t.json").read_text())
    assert report["analysis"] == "trace" and len(report["limit_points"]) == 2
    assert f"{report['limit_points'][0]['value']:.6g}" in result.stdout and "limit points" in result.stdout
