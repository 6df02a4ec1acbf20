"""The command line's results as an engineer reads them (issue 49, item 5): `flexmech
linearization` prints the K_T `solve --stiffness` prints; a document's problems come all at
once, each with its pointer and suggestion; --help shows no type for a flag and says which
command is an alias; a simulation's run time is one measured number in its progress and its
summary; the time left follows the recent rate of simulated time per wall time."""

from __future__ import annotations

import json
import re
from io import StringIO

import pytest
from conftest import EXAMPLES
from rich.console import Console
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.api.cli.progress import SimulationProgress, time_left
from flexmech.models import MechanismError, load_document

ENV = {"COLUMNS": "200", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "NO_COLOR": "1"}
GRIPPER = str(EXAMPLES / "gripper.json")
ROD = str(EXAMPLES / "rod_free_vibration.json")


def invoke(*args: str):
    return CliRunner().invoke(app, list(args), env=ENV)


def stiffness_block(output: str) -> list[str]:
    """The lines from K_T's title to the end of its terms."""
    lines = output.splitlines()
    first = next(k for k, line in enumerate(lines) if line.startswith("tangent stiffness K_T"))
    last = next(k for k, line in enumerate(lines) if line.startswith("zero term"))
    return lines[first : last + 1]


# --- K_T from `flexmech linearization` -------------------------------------------------------
def test_flexmech_linearization_prints_the_k_t_solve_stiffness_prints(tmp_path):
    """At the equilibrium, the K_T and terms of `flexmech linearization` are those of `flexmech
    solve --stiffness`, line for line; undeformed (acceptance: `--at undeformed`), its printed
    K_T is its report's."""
    by_solve = invoke("solve", GRIPPER, "--stiffness")
    by_command = invoke("linearization", GRIPPER)
    assert by_solve.exit_code == by_command.exit_code == 0, by_solve.output + by_command.output
    block = stiffness_block(by_command.output)
    assert block == stiffness_block(by_solve.output)
    assert any(line.startswith("term I of K_T") for line in block)
    assert "also in the report (--json): stiffness" not in by_command.output

    out = tmp_path / "undeformed.json"
    undeformed = invoke("linearization", GRIPPER, "--at", "undeformed", "--json", str(out))
    assert undeformed.exit_code == 0, undeformed.output
    K = json.loads(out.read_text())["stiffness"]["K"]
    rows = [line for line in stiffness_block(undeformed.output) if line.startswith("│ input.x [uN]")]
    first_row = [float(cell) for cell in rows[0].split("│")[2:-1]]  # the first block of columns
    assert first_row == pytest.approx(K[0][: len(first_row)], rel=1e-5, abs=1e-9)


# --- a document's problems, all at once ------------------------------------------------------
def test_every_problem_of_a_document_is_printed_with_its_pointer_and_suggestion(tmp_path):
    """Five fields wrong in five ways: each is a line "error: <pointer>: <problem>" with its
    suggestion, in the order the reader found them, none left as "and N more"."""
    doc = json.loads((EXAMPLES / "gripper.json").read_text())
    doc["elements"]["a"]["raduis"] = doc["elements"]["a"].pop("radius")
    doc["elements"]["b"]["arc_angle"] = [1]
    doc["loads"]["actuation"]["type"] = "forse"
    doc["outputs"]["end_effector"]["colour"] = 3
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(MechanismError) as found:
        load_document(path)
    problems = found.value.problems
    assert len(problems) == 5
    for command in (["solve", str(path)], ["modes", str(path)], ["sweep", str(path)]):
        result = invoke(*command)
        assert result.exit_code == 2, result.output
        lines = [line for line in result.stderr.splitlines() if line.strip()]
        assert lines == [f"error: {pointer}: {problem}" for pointer, problem in problems], command
    said = " ".join(lines)
    assert "did you mean 'radius'?" in said and "did you mean 'force'?" in said and "more field" not in said


def test_one_problem_is_one_line():
    result = invoke("solve", GRIPPER, "--set", "/sections/flexure/h=-5")
    assert result.exit_code == 2 and len(result.stderr.strip().splitlines()) == 1, result.stderr


# --- --help ----------------------------------------------------------------------------------
def test_help_shows_no_type_for_a_flag_and_marks_an_alias():
    """A flag takes no value: no <bool> beside --help, --stiffness or --line-search/--no-line-search;
    frf is listed as an alias of frequency-response, and its own --help says so first."""
    listing = invoke("--help")
    assert listing.exit_code == 0 and "<bool>" not in listing.output
    (frf,) = [line for line in listing.output.splitlines() if re.match(r"^│ frf\b", line)]
    assert "Alias of frequency-response." in frf and "resonance" not in frf
    for command in ("solve", "modes", "linearization", "simulate"):
        shown = invoke(command, "--help")
        assert shown.exit_code == 0 and "<bool>" not in shown.output, command
        assert "--help" in shown.output
    alias = invoke("frf", "--help")
    assert alias.exit_code == 0 and "Alias of frequency-response." in " ".join(alias.output.split())
    assert "--output" in alias.output and "per --output, repeated" in " ".join(alias.output.split())


# --- one run time per run --------------------------------------------------------------------
def test_a_simulations_summary_gives_the_stepping_time_its_progress_gives(tmp_path):
    """The progress's last line splits the run into setting up, stepping, building the report
    and writing; the stepping's time is the summary's ("N steps in T") and the report's
    seconds, and the parts add up to the whole."""
    out = tmp_path / "rod.json"
    result = invoke("simulate", ROD, "--until", "0.2", "--no-build", "--json", str(out))
    assert result.exit_code == 0, result.output
    last = result.stderr.strip().splitlines()[-1]
    done = re.match(r"simulating: finished at t = 0\.2 s, 200 steps in (\S+ s); (\S+) s in all \((.*)\)$", last)
    assert done, last
    parts = dict(part.rsplit(" ", 2)[0:1] + [part.rsplit(" ", 2)[1]] for part in done[3].split(", "))
    assert list(parts) == ["setting up", "stepping", "building the report", f"writing {out}"]
    summary = re.search(r"200 steps in (\S+ s) \(", result.stdout)
    assert summary and summary[1] == done[1] == f"{parts['stepping']} s"
    from flexmech.api.cli.progress import seconds_text

    assert done[1] == seconds_text(json.loads(out.read_text())["seconds"])
    assert sum(float(v) for v in parts.values()) == pytest.approx(float(done[2]), rel=0.05, abs=0.02)


def test_the_parts_of_a_run_add_up_and_its_stepping_is_the_runs_own_measure():
    now = iter([0.0, 0.5, 2.5, 2.5, 3.0, 3.0])  # start, two reports, the report's part, finish
    log = StringIO()
    with SimulationProgress(Console(file=log, width=300), until=1.0, clock=lambda: next(now)) as progress:
        heard = progress.stepping()
        heard(0.5, 500)
        heard(1.0, 1000)  # the end: building the report begins (at 2.5 s)
        progress.finish("finished at t = 1 s, 1000 steps", stepping=1.75)
    last = log.getvalue().splitlines()[-1]
    assert last == (
        "simulating: finished at t = 1 s, 1000 steps in 1.8 s; 3.0 s in all "
        "(setting up 0.75 s, stepping 1.8 s, building the report 0.5 s)"
    )


# --- the time left ---------------------------------------------------------------------------
def slowing_run() -> tuple[list[tuple[float, float]], float]:
    """(wall, simulated) every 0.1 s of wall time of a 2 s run whose adaptive steps shrink at
    t = 0.5 s: 1 s of simulated time per second of wall time, then 0.05 s per second (after
    0.5 s of setting up that the rate must not count); and when it ends."""
    heard, wall, t = [], 0.5, 0.0
    while t < 2.0 - 1e-12:
        wall += 0.1
        t = min(2.0, t + (0.1 if t < 0.5 - 1e-12 else 0.005))
        heard.append((wall, t))
    return heard, wall


def test_the_time_left_follows_the_recent_rate_of_a_run_that_slows_down():
    """Once the slow part has run a while (its quarter of the wall time), the time left is within
    20 % of the truth at every report; the rate since the start (what the ETA was: elapsed
    (1 - f) / f, setting up included) promised less than 60 % of it for a long while."""
    heard, end = slowing_run()
    until = 2.0
    checked, promised_too_little = 0, 0
    for k, (wall, t) in enumerate(heard):
        if not 0.8 <= t < until:
            continue
        truth = end - wall
        left = time_left(heard[: k + 1], until)
        assert left == pytest.approx(truth, rel=0.2), (t, left, truth)
        since_start = wall * (1 - t / until) / (t / until)
        promised_too_little += since_start < 0.6 * truth
        checked += 1
    assert checked > 200 and promised_too_little > 50
    assert time_left(heard, until) == 0.0 and time_left(heard[:1], until) is None


def test_a_steady_run_is_given_its_time_left_exactly_whatever_its_setting_up_took():
    heard = [(10.0 + 0.5 * k, 0.1 * k) for k in range(1, 6)]  # 0.2 s of simulated time per second, after 10 s
    assert time_left(heard, 2.0) == pytest.approx((2.0 - 0.5) / 0.2, rel=1e-12)


def test_the_progress_lines_give_the_recent_rates_time_left():
    """A log's lines: the first ETA unknown (one report: the first window carries the start's
    one-off costs), then the recent rate's; the lines keep only the reports that rate needs."""
    heard, end = slowing_run()
    clock = iter([0.0] + [wall for wall, _ in heard])
    log = StringIO()
    with SimulationProgress(Console(file=log, width=300), until=2.0, clock=lambda: next(clock)) as progress:
        for k, (_, t) in enumerate(heard):
            progress(t, k + 1)
            assert len(progress.heard) <= 2 + 0.25 * (k + 1)  # the recent quarter, and one before it
    lines = log.getvalue().splitlines()
    assert lines[0].endswith("ETA ? s")
    for line in lines[1:]:
        t = float(re.search(r"t = (\S+) of", line)[1])
        wall = next(w for w, s in heard if abs(s - t) < 1e-9)
        left = float(re.search(r"ETA (\S+) s$", line)[1])
        if t >= 0.8:
            assert abs(left - (end - wall)) <= max(0.2 * (end - wall), 0.5), line
