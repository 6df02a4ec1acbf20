"""The command line's polish (issue 28, item 9): --help without the physics imported, progress
over the whole run in a log, cut tables that say what they leave out, --csv files whose header
carries the units and whose numbers are the --json file's, and --every thinning the report."""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from io import StringIO
from pathlib import Path

import pytest
from conftest import EXAMPLES
from impact_cases import csfh
from rich.console import Console
from typer.testing import CliRunner

from flexmech.api.cli import app

ROOT = Path(__file__).resolve().parents[2]
ENV = {"COLUMNS": "200", "NO_COLOR": "1"}
ROD = str(EXAMPLES / "rod_free_vibration.json")  # keeps every 5th step of 1 ms
GRIPPER = str(EXAMPLES / "gripper.json")
HEAVY = (
    "numpy",
    "casadi",
    "scipy",
    "flexmech.models",
    "matplotlib",
    "httpx",
    "flexmech.service.analyses",
    "flexmech.service.solvers",
)


def fresh(code: str, *args: str) -> subprocess.CompletedProcess:
    """`code` in a new Python process at the repository's root, without plugins."""
    env = {k: v for k, v in os.environ.items() if k != "FLEXMECH_PLUGINS"} | ENV
    return subprocess.run(
        [sys.executable, "-c", code, *args], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300
    )


def read_csv(path: Path) -> tuple[list[str], list[list[str]]]:
    with path.open(newline="") as file:
        rows = list(csv.reader(file))
    return rows[0], rows[1:]


def column(header: list[str], rows: list[list[str]], name: str) -> list[float]:
    k = header.index(name)
    return [float(row[k]) for row in rows]


# --- --help without the physics ------------------------------------------------------------
@pytest.mark.parametrize("args", [["--help"], ["solve", "--help"], ["sweep", "--help"], ["simulate", "--help"]])
def test_help_imports_no_physics(args):
    """The list of commands and a command's options are answered before NumPy, CasADi, the
    models or the analyses registry are imported (they are what made --help take a second)."""
    done = fresh(
        "import sys, json, flexmech.api.cli\n"
        "try:\n    flexmech.api.cli.app(sys.argv[1:], prog_name='flexmech')\nexcept SystemExit:\n    pass\n"
        f"print(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))",
        *args,
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.strip().splitlines()
    assert "Usage: flexmech" in done.stdout and json.loads(lines[-1]) == []


def test_the_list_of_commands_is_the_registrys():
    """Before the registry is imported, the analyses' commands are listed from the catalog:
    the same names, order, summaries and aliases as the registry gives once imported."""
    listing = "import sys, flexmech.api.cli\ntry:\n    flexmech.api.cli.app(['--help'], prog_name='flexmech')\nexcept SystemExit:\n    pass"
    light, loaded = fresh(listing), fresh("import flexmech.service.analyses\n" + listing)
    assert light.returncode == loaded.returncode == 0, light.stderr + loaded.stderr
    assert "frequency-response" in light.stdout and "frf" in light.stdout and "modes" in light.stdout
    assert light.stdout == loaded.stdout


def test_the_catalogs_names_are_the_models():
    from flexmech.api.cli.catalog import ANALYSIS_NAMES, COMPARED_MODEL_NAMES, MODEL_NAMES
    from flexmech.models import COMPARED_MODELS, MODELS
    from flexmech.service.analyses import ANALYSES

    assert MODEL_NAMES == MODELS and COMPARED_MODEL_NAMES == COMPARED_MODELS
    built_in = [a.name for a in ANALYSES if type(a).__module__.startswith("flexmech.service.analyses.")]
    assert list(ANALYSIS_NAMES) == built_in


def test_a_listed_analysis_command_runs_with_its_options(tmp_path):
    """An analysis' command, listed from the catalog, takes its options once it runs."""
    out = tmp_path / "k.json"
    done = fresh(
        "import sys, flexmech.api.cli\nflexmech.api.cli.app(sys.argv[1:], prog_name='flexmech')",
        "linearization",
        GRIPPER,
        "--at",
        "undeformed",
        "--json",
        str(out),
    )
    assert done.returncode == 0, done.stderr
    report = json.loads(out.read_text())
    assert report["analysis"] == "linearization" and report["at"] == "undeformed"


# --- progress in a log -----------------------------------------------------------------------
def test_progress_in_a_log_has_a_line_per_tenth():
    from flexmech.api.cli.progress import SimulationProgress

    log = StringIO()
    with SimulationProgress(Console(file=log, force_terminal=False, width=200), until=1.0) as progress:
        for k in range(1, 101):
            progress(k / 100, 10 * k)
    lines = log.getvalue().splitlines()
    assert [line.split("(")[1].split(" %")[0] for line in lines] == ["1", *(str(10 * k) for k in range(1, 11))]
    assert lines[-1].startswith("simulating: t = 1 of 1 s (100 %), 1000 steps,") and "ETA 0 s" in lines[-1]


def test_a_simulation_in_a_log_reports_its_steps_then_its_report_and_files(tmp_path):
    out, table = tmp_path / "rod.json", tmp_path / "rod.csv"
    result = CliRunner().invoke(
        app, ["simulate", ROD, "--until", "1", "--json", str(out), "--csv", str(table)], env=ENV
    )
    assert result.exit_code == 0, result.output
    lines = result.stderr.strip().splitlines()
    tenths = {int(line.split("(")[1].split(" %")[0]) // 10 for line in lines if " %)" in line}
    assert tenths >= set(range(1, 11))
    after = lines[[k for k, line in enumerate(lines) if "(100 %)" in line][0] + 1 :]
    assert after[0].startswith("simulating: building the report")
    assert after[1].startswith(f"simulating: writing {out}") and after[2].startswith(f"simulating: writing {table}")
    assert after[3].startswith("simulating: finished at t = 1 s, 1000 steps in ")
    assert "building the report" in after[3] and f"writing {table}" in after[3]


# --- cut tables ----------------------------------------------------------------------------
def moreau_document(tmp_path: Path, until: float) -> str:
    path = tmp_path / "moreau.json"
    path.write_text(json.dumps(csfh("6.1", scheme="moreau", step=1e-5, until=until)))
    return str(path)


def test_the_impacts_table_says_how_many_it_leaves_out(tmp_path):
    out = tmp_path / "run.json"
    result = CliRunner().invoke(app, ["simulate", moreau_document(tmp_path, 1.0), "--json", str(out)], env=ENV)
    assert result.exit_code == 0, result.output
    impacts = json.loads(out.read_text())["impacts"]
    assert len(impacts) > 6
    assert f"... and {len(impacts) - 6} more impacts (--json has them all)" in result.stdout
    assert f"{impacts[5]['time']:.7f}" in result.stdout and f"{impacts[6]['time']:.7f}" not in result.stdout


def test_the_outputs_table_says_how_many_it_leaves_out():
    from flexmech.api.cli.simulate_output import print_run

    report = {
        "name": "many",
        "status": "finished",
        "time_reached": 1.0,
        "steps": 10,
        "seconds": 0.1,
        "energy_balance_error": 0.0,
        "message": "",
        "outputs": {f"out{k}": [0.0, float(k)] for k in range(20)},
        "output_units": {f"out{k}": "mm" for k in range(20)},
    }
    log = StringIO()
    print_run(Console(file=log, width=200), report)
    assert "out17" in log.getvalue() and "out18" not in log.getvalue()
    assert "... and 2 more outputs (--json has them all)" in log.getvalue()


def test_a_sweeps_table_says_it_shows_some_points(tmp_path):
    result = CliRunner().invoke(
        app,
        ["sweep", GRIPPER, "--path", "/loads/actuation/force/1", "--start", "0", "--stop", "20", "--steps", "20"],
        env=ENV,
    )
    assert result.exit_code == 0, result.output
    assert "6 of 21 points shown, spread evenly (--json has them all)" in result.stdout


# --- --csv ---------------------------------------------------------------------------------
def test_simulate_csv_has_units_in_its_header_and_the_json_numbers(tmp_path):
    out, table = tmp_path / "rod.json", tmp_path / "rod.csv"
    args = ["simulate", ROD, "--until", "0.2", "--json", str(out), "--csv", str(table)]
    result = CliRunner().invoke(app, args, env=ENV)
    assert result.exit_code == 0, result.output
    report, (header, rows) = json.loads(out.read_text()), read_csv(table)
    assert header[0] == "t [s]" and "bodies.tip.y [m]" in header and "bodies.tip.angle [rad]" in header
    assert "energies.kinetic [N*m]" in header and all(head.endswith("]") for head in header)
    assert column(header, rows, "t [s]") == report["times"] and len(rows) == 41
    for name, values in report["outputs"].items():
        assert column(header, rows, f"{name} [{report['output_units'][name]}]") == values


def test_an_impact_runs_csv_names_coordinates_velocities_and_contacts_with_units(tmp_path):
    out, table = tmp_path / "run.json", tmp_path / "run.csv"
    document = moreau_document(tmp_path, 0.1)
    result = CliRunner().invoke(app, ["simulate", document, "--json", str(out), "--csv", str(table)], env=ENV)
    assert result.exit_code == 0, result.output
    report, (header, rows) = json.loads(out.read_text()), read_csv(table)
    assert header[:4] == ["t [s]", "hinge.x [m]", "hinge.y [m]", "hinge.theta [deg]"]
    assert "hinge.y.velocity [m/s]" in header and "conjugate.normal_force [N]" in header
    assert column(header, rows, "hinge.y [m]") == report["coordinates"]["hinge.y"]
    assert column(header, rows, "conjugate.normal_force [N]") == report["contacts"]["conjugate"]["normal_force"]


def test_sweep_csv_has_the_field_and_outputs_with_units_and_the_json_numbers(tmp_path):
    out, table = tmp_path / "sweep.json", tmp_path / "sweep.csv"
    args = ["sweep", GRIPPER, "--path", "/loads/actuation/force/1", "--start", "0", "--stop", "40", "--steps", "8"]
    result = CliRunner().invoke(app, [*args, "--json", str(out), "--csv", str(table)], env=ENV)
    assert result.exit_code == 0, result.output
    curve, (header, rows) = json.loads(out.read_text())["curves"][0]["sweep"], read_csv(table)
    assert header[0] == "/loads/actuation/force/1 [uN]" and "end_effector.x [mm]" in header
    assert header[-2:] == ["status", "iterations"] and {row[-2] for row in rows} == {"converged"}
    assert column(header, rows, header[0]) == curve["values"] == [5.0 * k for k in range(9)]
    assert column(header, rows, "end_effector.x [mm]") == curve["outputs"]["end_effector.x"]
    compared = CliRunner().invoke(app, [*args, "--compare-models", "--csv", str(table)], env=ENV)
    assert compared.exit_code == 0, compared.output
    header, rows = read_csv(table)
    assert header[:2] == ["curve", "/loads/actuation/force/1 [uN]"] and len(rows) == 3 * 9
    assert [row[0] for row in rows[::9]] == ["silicon, linear", "silicon, partial_nonlinear", "silicon, exact"]


# --- --every -------------------------------------------------------------------------------
def test_every_thins_an_impact_report_by_its_factor_keeping_the_first_and_last_state(tmp_path):
    """10^3 Moreau steps without an impact: every state kept, or one in ten."""
    document, full, thin = moreau_document(tmp_path, 0.01), tmp_path / "full.json", tmp_path / "thin.json"
    for out, extra in ((full, []), (thin, ["--every", "10"])):
        result = CliRunner().invoke(app, ["simulate", document, *extra, "--json", str(out)], env=ENV)
        assert result.exit_code == 0, result.output
    a, b = json.loads(full.read_text()), json.loads(thin.read_text())
    assert len(a["times"]) == 1001 and len(b["times"]) == 101 and not a["events"]
    assert b["times"][0] == a["times"][0] and b["times"][-1] == a["times"][-1]
    assert b["coordinates"]["hinge.y"] == a["coordinates"]["hinge.y"][::10]
    assert 7 < full.stat().st_size / thin.stat().st_size < 11


def test_every_thins_a_link_run_without_changing_its_steps(tmp_path):
    full, thin = tmp_path / "full.json", tmp_path / "thin.json"
    for out, every in ((full, "1"), (thin, "10")):
        result = CliRunner().invoke(app, ["simulate", ROD, "--until", "0.2", "--every", every, "--json", str(out)])
        assert result.exit_code == 0, result.output
    a, b = json.loads(full.read_text()), json.loads(thin.read_text())
    assert len(a["times"]) == 201 and b["times"] == a["times"][::10] and b["steps"] == a["steps"] == 200
    assert b["outputs"]["bodies.tip.y"] == a["outputs"]["bodies.tip.y"][::10]
