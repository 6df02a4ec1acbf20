"""A document someone else wrote, printed by the command line: its names are text for the
terminal, never rich markup and never a control sequence (an escape sequence in an output's name
once reached the terminal as it was: it could set the window's title, write the clipboard or
overwrite the lines above)."""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from flexmech.api.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
ENV = {"COLUMNS": "200", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "NO_COLOR": "1"}
HOSTILE = "tip\x1b]0;owned\x07\x1b[2K\x1b[1A\r[bold red]loud"


def _gripper_with_a_hostile_output(folder: Path) -> Path:
    document = json.loads((EXAMPLES / "gripper.json").read_text())
    document["outputs"][HOSTILE] = dict(document["outputs"]["end_effector"])
    path = folder / "shared.json"
    path.write_text(json.dumps(document))
    return path


def test_a_hostile_name_prints_as_text_in_tables_and_errors(tmp_path):
    path = _gripper_with_a_hostile_output(tmp_path)
    runner = CliRunner()
    solved = runner.invoke(app, ["solve", str(path)], env=ENV)
    refused = runner.invoke(app, ["solve", str(path), "--set", f"/loads/{HOSTILE}/force/1=1"], env=ENV)
    assert solved.exit_code == 0, solved.output
    assert refused.exit_code == 2, refused.output
    for output in (solved.output, refused.output):
        assert "\x1b" not in output and "\x07" not in output and "\r" not in output
    shown = "tip ]0;owned  [2K [1A [bold red]loud"  # every control character a space, the markup as text
    assert f"{shown}.x" in solved.output
    assert shown in refused.output.replace("\n", "")
