"""Integration settings users hit: Newmark's stable pairs, the adaptive run's limits, and the
command line's progress and limits."""

from __future__ import annotations

import json

import numpy as np
from conftest import EXAMPLES
from impact_cases import csfh
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.api.cli.progress import SimulationProgress
from flexmech.models import compile_mechanism, load_document
from flexmech.service.analyses import ANALYSES
from flexmech.service.analyses.base import AnalysisRequest
from flexmech.service.dynamics.run import MAX_STEPS

ROD = EXAMPLES / "rod_free_vibration.json"


def simulate(path, **fields) -> dict:
    mech = compile_mechanism(load_document(json.loads(path.read_text())))
    return ANALYSES.named("simulate").run(mech, AnalysisRequest(given={"simulate": fields}))


def periods(report: dict) -> np.ndarray:
    t, y = np.array(report["times"]), np.array(report["outputs"]["bodies.tip.y"])
    crossings = [t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i]) for i in range(len(y) - 1) if y[i] > 0 >= y[i + 1]]
    return np.diff(crossings)


def test_newmark_0505_runs_the_thesis_example_I1():
    """Lan 2005's (a1, a2) = (0.505, 0.505), refused before as 'not unconditionally stable',
    is (gamma = 0.505 >= 1/2, beta = 0.2525 >= gamma / 2): it runs the rod, its period that of
    the default scheme, and it dissipates a little (gamma > 1/2), never gains."""
    newmark = simulate(ROD, until=1.0, every=1, scheme="newmark", a1=0.505, a2=0.505)
    alpha = simulate(ROD, until=1.0, every=1)
    assert newmark["status"] == "finished" and newmark["scheme"] == {"name": "newmark", "a1": 0.505, "a2": 0.505}
    np.testing.assert_allclose(periods(newmark), periods(alpha).mean(), rtol=2e-3)
    energy = np.array(newmark["energies"]["kinetic"]) + np.array(newmark["energies"]["potential"])
    assert energy[-1] < energy[0] and energy.max() <= energy[0] * (1 + 1e-9)


def test_an_adaptive_run_stops_at_its_step_limit_with_the_history_so_far():
    report = simulate(ROD, until=1.0, adaptive=True, tolerance=1e-12, max_steps=300, every=1)
    assert report["status"] == "step_limit"
    assert "limit of 300 adaptive steps" in report["message"] and "loosen the tolerance" in report["message"]
    assert report["steps"] == 300 and 0 < report["time_reached"] < 1.0
    assert len(report["times"]) == 301 and report["times"][-1] == report["time_reached"]
    assert len(report["outputs"]["bodies.tip.y"]) == 301


def test_an_adaptive_run_stops_at_its_shortest_step():
    report = simulate(ROD, until=1.0, adaptive=True, tolerance=1e-12, min_step=1e-4, step=1e-3)
    assert report["status"] == "min_step" and "fell below min_step = 0.0001 s" in report["message"]
    assert report["time_reached"] < 1.0 and report["times"][-1] == report["time_reached"]


def test_the_command_line_applies_the_services_step_limit():
    result = CliRunner().invoke(
        app, ["simulate", str(ROD), "--until", "2000", "--step", "0.001"], env={"COLUMNS": "200", "NO_COLOR": "1"}
    )
    assert result.exit_code == 2
    assert f"over the limit of {MAX_STEPS}" in result.output
    result = CliRunner().invoke(
        app, ["simulate", str(ROD), "--until", "0.1", "--max-steps", "50"], env={"COLUMNS": "200", "NO_COLOR": "1"}
    )
    assert result.exit_code == 2 and "100 steps of 0.001 s, over the limit of 50" in result.output


def test_an_impact_run_is_costed_before_it_starts_and_max_steps_raises_the_limit_on_this_machine(monkeypatch, tmp_path):
    """Issue 24's `csfh.json --until 1e6` (event-driven: costed at its first step, 1e10 steps)
    is refused at once; under a lowered service limit, --max-steps raises it for a local run."""
    env = {"COLUMNS": "200", "NO_COLOR": "1"}
    result = CliRunner().invoke(
        app, ["simulate", str(EXAMPLES / "csfh_asymmetric_impact.json"), "--until", "1e6"], env=env
    )
    assert result.exit_code == 2, result.output
    assert (
        f"/simulate/until: 1e+06 s from a first step of 0.0001 s is costed at 1e+10 steps, over the limit of "
        f"{MAX_STEPS}"
    ) in " ".join(result.output.split())
    import flexmech.service.dynamics.run as run

    monkeypatch.setattr(run, "MAX_STEPS", 100)
    moreau = tmp_path / "csfh_moreau.json"  # scenario 6.3 with the laws moreau takes
    moreau.write_text(json.dumps(csfh("6.3", scheme="moreau")))
    args = ["simulate", str(moreau), "--step", "1e-4", "--until", "0.02"]
    refused = CliRunner().invoke(app, args, env=env)
    assert refused.exit_code == 2 and "the run needs 200 steps of 0.0001 s, over the limit of 100" in refused.output
    raised = CliRunner().invoke(app, args + ["--max-steps", "300"], env=env)
    assert raised.exit_code == 0, raised.output
    assert "finished at t = 0.02 s, 200 steps (moreau)" in raised.output


def test_a_run_of_uncountably_many_steps_is_refused_on_the_command_line():
    for document, scheme in ((ROD, None), (EXAMPLES / "csfh.json", "moreau"), (EXAMPLES / "csfh.json", "event_driven")):
        args = ["simulate", str(document), "--until", "1e300", "--step", "1e-300"]
        result = CliRunner().invoke(
            app, args + (["--scheme", scheme] if scheme else []), env={"COLUMNS": "200", "NO_COLOR": "1"}
        )
        assert result.exit_code == 2, (document, scheme, result.output)
        assert "1e+300 s in steps of 1e-300 s would be more than 1e+12 steps" in result.output


def test_progress_lines_when_not_a_terminal(capsys):
    """In a log: a line for the first window at once, then one every few seconds, and the last."""
    from rich.console import Console

    console = Console(file=None, force_terminal=False, stderr=True)
    with SimulationProgress(console, until=2.0) as progress:
        progress(0.02, 20)
        progress(0.04, 40)  # within LINE_SECONDS of the first: not printed
        progress(2.0, 2000)
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2
    assert lines[0].startswith("simulating: t = 0.02 of 2 s (1 %), 20 steps") and "ETA" in lines[0]
    assert lines[1].startswith("simulating: t = 2 of 2 s (100 %), 2000 steps")
