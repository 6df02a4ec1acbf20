"""The optimize job over real HTTP (uvicorn, SQLite, process pool) and the optimize and trace
commands of the CLI."""

from __future__ import annotations

import json

import pytest
from conftest import EXAMPLES
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.api.client import Client, FlexmechError
from flexmech.models import compile_mechanism, load_document
from flexmech.service.design.optimize import optimize
from flexmech.service.design.problem import design_problem

ENV = {"COLUMNS": "200", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "NO_COLOR": "1"}
GRASPER = EXAMPLES / "grasper_shape.json"


@pytest.fixture(scope="module")
def client(api_server):
    with Client(api_server.url) as c:
        yield c


@pytest.fixture(scope="module")
def core_optimum():
    doc = load_document(GRASPER)
    return optimize(design_problem(compile_mechanism(doc), doc.optimize))


def test_optimize_job_over_http_equals_the_core(client, core_optimum):
    job = client.optimize(example="grasper_shape", problem={**json.loads(GRASPER.read_text())["optimize"], "starts": 2})
    assert job.kind == "optimize" and job.progress.total == 2
    final = client.wait(job.id, timeout=300)
    assert final.status == "succeeded"
    result = client.result(job.id).result
    assert result["status"] == "optimal"
    for path, value in core_optimum.best.design.items():
        assert result["design"][path] == pytest.approx(value, rel=1e-8)
    assert result["objective"] == pytest.approx(core_optimum.best.objective, rel=1e-8)
    assert [s["start"] for s in result["starts"]] == [0, 1]
    assert result["units"]["objective"] == "N"
    assert result["multipliers"]["constraints"][0] == pytest.approx(
        core_optimum.best.multipliers["constraints"][0], rel=1e-6
    )
    assert len(result["history"]) == result["iterations"] + 1


@pytest.mark.parametrize(
    "problem_change, pointer, message",
    [
        (
            {"design": [{"path": "/elements/link/colour", "lower": 0, "upper": 1}]},
            "/problem/design/0/path",
            "'/elements/link/colour' is not a numeric field of this mechanism",
        ),
        (
            {"design": [{"path": "/elements/link/length", "lower": 0.09, "upper": 0.085}]},
            "/problem/design/0/lower",
            "lower bound 0.09 is above the upper bound 0.085",
        ),
        ({"objective": {"output": "tip.force"}}, "/problem/objective/output", "unknown output 'tip.force'"),
    ],
)
def test_bad_problems_are_422_naming_the_field(client, problem_change, pointer, message):
    problem = {**json.loads(GRASPER.read_text())["optimize"], **problem_change}
    with pytest.raises(FlexmechError) as info:
        client.optimize(example="grasper_shape", problem=problem)
    assert info.value.status == 422
    assert info.value.pointer == pointer
    assert message in info.value.message


def test_a_document_without_an_optimize_section_is_422(client):
    with pytest.raises(FlexmechError) as info:
        client.optimize(example="gripper")
    assert info.value.status == 422 and info.value.pointer == "/document/optimize"
    assert "the document has no optimize section" in info.value.message


def run(*args: str):
    return CliRunner().invoke(app, list(args), env=ENV)


def test_cli_optimize_prints_the_optimum_and_writes_json(tmp_path, core_optimum):
    out = tmp_path / "opt.json"
    result = run("optimize", str(GRASPER), "--sensitivity", "/loads/push/dy", "--json", str(out))
    assert result.exit_code == 0, result.output
    assert "status: optimal" in result.output
    c1 = core_optimum.best.design["/elements/link/shape/coefficients/0"]
    assert f"{c1:.6g}" in result.output
    data = json.loads(out.read_text())
    assert data["design"]["/elements/link/shape/coefficients/0"] == pytest.approx(c1, rel=1e-9)
    assert "/loads/push/dy" in data["sensitivities"]["derivatives"]["objective"]


def test_cli_optimize_errors_are_one_line_with_exit_code_2(tmp_path):
    data = json.loads(GRASPER.read_text())
    data["optimize"]["design"][0]["lower"] = 1.0
    doc = tmp_path / "bad.json"
    doc.write_text(json.dumps(data))
    result = run("optimize", str(doc))
    assert result.exit_code == 2
    assert "/optimize/design/0/lower: lower bound 1 is above the upper bound 0.085" in result.output
    result = run("optimize", str(EXAMPLES / "gripper.json"))
    assert result.exit_code == 2 and "the document has no optimize section" in result.output


def test_cli_trace_reports_the_limit_points(tmp_path):
    out = tmp_path / "path.json"
    result = run(
        "trace",
        str(EXAMPLES / "snap_through_arch.json"),
        "--path",
        "/loads/P/force/1",
        "--stop",
        "-300",
        "--step",
        "20",
        "--json",
        str(out),
    )
    assert result.exit_code == 0, result.output
    data = json.loads(out.read_text())
    assert [lp["kind"] for lp in data["limit_points"]] == ["minimum", "maximum"]
    for lp in data["limit_points"]:
        assert f"{lp['value']:.6g}" in result.output
    bad = run(
        "trace", str(EXAMPLES / "snap_through_arch.json"), "--path", "/loads/Q/force/1", "--stop", "-3", "--step", "1"
    )
    assert bad.exit_code == 2 and "--path: not a numeric field" in bad.output


def test_solve_returns_closing_force_sensitivities_equal_to_the_core(client):
    from flexmech.service.design.sensitivity import equilibrium_sensitivities
    from flexmech.service.solvers.sweep import solve_for_target

    actuation = "/loads/actuation/force/1"
    answer = client.solve(
        example="gripper",
        target={"path": actuation, "output": "end_effector.x", "equals": 0},
        sensitivities={"parameters": ["/sections/flexure/h"], "outputs": [actuation]},
    )
    mech = compile_mechanism(load_document(EXAMPLES / "gripper.json"))
    found = solve_for_target(mech, actuation, "end_effector.x", 0.0)
    core = equilibrium_sensitivities(
        found.equilibrium.mechanism,
        found.equilibrium.z,
        ["/sections/flexure/h"],
        [actuation],
        target=(actuation, "end_effector.x"),
    )
    assert answer.sensitivities["derivatives"][actuation]["/sections/flexure/h"] == pytest.approx(
        core.matrix[0, 0], rel=1e-9
    )
    assert answer.sensitivities["units"][actuation]["/sections/flexure/h"] == "uN/mm"
    with pytest.raises(FlexmechError) as info:
        client.solve(example="gripper", sensitivities={"parameters": ["/sections/flexure/q"], "outputs": ["x"]})
    assert info.value.status == 422 and info.value.pointer == "/sensitivities/parameters/0"
    assert "not a numeric field" in info.value.message
