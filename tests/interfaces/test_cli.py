"""The flexmech command line on the seed-000 gripper: numbers come from the solver, problems
are one-line errors with exit code 2, non-convergence is reported with exit code 1."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flexmech.api.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
GRIPPER = str(EXAMPLES / "gripper.json")
ACTUATION = "/loads/actuation/force/1"
# The closing force of the partial non-linear silicon gripper (end_effector.x = 0), uN.
CLOSING_FORCE = 77.0346
# Closing is judged on the jaw position to well below the jaw travel (~0.44 mm), mm.
CLOSING_TOLERANCE_MM = 1e-3
# Wide, colourless output so the printed numbers are whole and plain.
ENV = {"COLUMNS": "200", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "NO_COLOR": "1"}


@pytest.fixture
def run():
    runner = CliRunner()

    def invoke(*args: str):
        return runner.invoke(app, list(args), env=ENV)

    return invoke


def _one_line_error(result) -> str:
    assert result.exit_code == 2, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: ")
    return lines[0]


def test_solve_closes_the_gripper_and_prints_the_solver_numbers(run, tmp_path):
    out = tmp_path / "out.json"
    result = run("solve", GRIPPER, "--set", f"{ACTUATION}={CLOSING_FORCE}", "--json", str(out))
    assert result.exit_code == 0, result.output
    summary = json.loads(out.read_text())
    assert summary["status"] == "converged"
    assert summary["overrides"] == {ACTUATION: CLOSING_FORCE}
    outputs = summary["outputs"]
    assert abs(outputs["end_effector.x"]) < CLOSING_TOLERANCE_MM
    # The table shows the solver's values, to six significant figures.
    for name in ("end_effector.y", "end_effector.dx", "anchor.Fy", "bodies.input.angle"):
        assert f"{outputs[name]:.6g}" in result.stdout, name
    assert f"{ACTUATION} = {CLOSING_FORCE:.6g} uN" in result.stdout
    assert "status: converged" in result.stdout


def test_solve_with_quantity_override_and_stiffness(run, tmp_path):
    out = tmp_path / "k.json"
    result = run("solve", GRIPPER, "--set", f"{ACTUATION}=0.05 mN", "--stiffness", "--json", str(out))
    assert result.exit_code == 0, result.output
    data = json.loads(out.read_text())
    assert data["outputs"]["bodies.input.y"] > 0.2  # pushed up from y = 0.2 mm
    k = data["stiffness"]
    n = len(k["coordinates"])
    assert n == 9 and len(k["K"]) == n and all(len(row) == n for row in k["K"])
    assert k["row_units"][0] == "uN" and k["column_units"][2] == "deg"
    assert "tangent stiffness" in result.stdout and "input.angle [uN*mm]" in result.stdout


def test_bad_pointer_in_set_names_the_pointer(run):
    line = _one_line_error(run("solve", GRIPPER, "--set", "/loads/actuation/force/7=3"))
    assert line.startswith("error: /loads/actuation/force/7: ")


def test_bad_option_value_is_a_one_line_error(run):
    line = _one_line_error(run("solve", GRIPPER, "--model", "quadratic"))
    assert line.startswith("error: --model: ") and "partial_nonlinear" in line


def test_unknown_body_in_the_document_names_the_field(run, tmp_path):
    document = json.loads((EXAMPLES / "gripper.json").read_text())
    document["elements"]["a"]["to"] = "nowhere"
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(document))
    line = _one_line_error(run("solve", str(path)))
    assert line.startswith("error: /elements/a/to: ") and "nowhere" in line


def test_sweep_writes_a_plot_and_finds_the_closing_force(run, tmp_path):
    plot, out = tmp_path / "sweep.png", tmp_path / "sweep.json"
    result = run("sweep", GRIPPER, "--plot", str(plot), "--json", str(out))
    assert result.exit_code == 0, result.output
    assert plot.stat().st_size > 1000
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    (curve,) = json.loads(out.read_text())["curves"]
    target = curve["target"]
    assert target["status"] == "converged"
    assert abs(target["value"] - CLOSING_FORCE) < 1e-3
    assert f"actuation force y = {target['value']:.6g} uN" in result.stdout
    assert abs(curve["sweep"]["outputs"]["end_effector.x"][-1]) < CLOSING_TOLERANCE_MM


def test_sweep_along_a_path_until_an_output_value(run, tmp_path):
    out = tmp_path / "until.json"
    result = run(
        "sweep",
        GRIPPER,
        "--path",
        ACTUATION,
        "--start",
        "0",
        "--until",
        "end_effector.x=0.3",
        "--steps",
        "4",
        "--json",
        str(out),
    )
    assert result.exit_code == 0, result.output
    (curve,) = json.loads(out.read_text())["curves"]
    assert len(curve["sweep"]["values"]) == 5
    assert abs(curve["sweep"]["outputs"]["end_effector.x"][-1] - 0.3) < CLOSING_TOLERANCE_MM


def test_sweep_options_need_a_path(run):
    line = _one_line_error(run("sweep", GRIPPER, "--stop", "10"))
    assert line.startswith("error: --stop: ")


def test_far_load_does_not_converge_and_exits_1(run):
    result = run("solve", GRIPPER, "--set", f"{ACTUATION}=5000", "--max-iterations", "5")
    assert result.exit_code == 1, result.output
    assert "not_converged" in result.stdout
    assert "no convergence in 5 iterations" in result.stdout
    assert "Traceback" not in result.output


def test_examples_lists_the_gripper_by_the_name_a_command_takes(run):
    result = run("examples")
    assert result.exit_code == 0, result.output
    row = next(
        line for line in result.stdout.splitlines() if "MEMS gripper with curved-beam flexures (silicon)" in line
    )
    assert row.split()[1] == "gripper" and "flexmech solve NAME" in result.stdout
    solved = run("solve", "gripper")
    assert solved.exit_code == 0 and "converged" in solved.stdout


def test_compare_models_plots_both_curves(run, tmp_path):
    plot, out = tmp_path / "flexmech.models.svg", tmp_path / "flexmech.models.json"
    result = run(
        "sweep",
        GRIPPER,
        "--compare-models",
        "--steps",
        "10",
        "--path",
        ACTUATION,
        "--start",
        "-60",
        "--until",
        "end_effector.x=0",
        "--plot",
        str(plot),
        "--json",
        str(out),
    )
    assert result.exit_code == 0, result.output
    assert plot.read_text().lstrip().startswith("<?xml")
    curves = {c["label"]: c for c in json.loads(out.read_text())["curves"]}
    assert set(curves) == {"silicon, linear", "silicon, partial_nonlinear", "silicon, exact"}
    # The partial non-linear model stiffens the gripper: closing takes more force.
    assert curves["silicon, partial_nonlinear"]["target"]["value"] == pytest.approx(CLOSING_FORCE, abs=1e-3)
    assert curves["silicon, linear"]["target"]["value"] < CLOSING_FORCE


def test_unreachable_sweep_target_is_non_convergence_not_an_error(run):
    result = run(
        "sweep",
        GRIPPER,
        "--path",
        ACTUATION,
        "--start",
        "0",
        "--until",
        "end_effector.x=-50",
        "--steps",
        "5",
        "--model",
        "linear",
    )
    assert result.exit_code == 1
    assert "target end_effector.x = -50 mm not reached: status not_converged" in result.output


def test_inverse_command_reports_the_unknown_load_and_non_convergence(run):
    four_bar = str(EXAMPLES / "inverse_four_bar.json")
    result = run("inverse", four_bar)
    assert result.exit_code == 0, result.output
    assert "given internal forces: L3.h = -5 N" in result.output
    assert "/loads/F/force/0" in result.output and "35.9" in result.output
    # h3 = +5 N lies beyond the branch's fold (h3 peaks near +3 N): a status, exit code 1.
    beyond = run("inverse", four_bar, "--internal-force", "L3.h=5", "--max-iterations", "30")
    assert beyond.exit_code == 1
    assert "status: not_converged after 30 iterations" in beyond.output
    wrong = run("inverse", four_bar, "--internal-force", "L3.x=5")
    assert wrong.exit_code == 2
    assert "--internal-force: expected LINK.h=VALUE or LINK.v=VALUE, got 'L3.x=5'" in wrong.output
    no_section = run("inverse", str(EXAMPLES / "cantilever.json"))
    assert no_section.exit_code == 2
    assert "/inverse: the document has no inverse section" in no_section.output
