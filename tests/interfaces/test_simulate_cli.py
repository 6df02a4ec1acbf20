"""`flexmech simulate`: the run's summary, its JSON equal to the analysis' report, the
figures and the animation written, and bad options refused naming the option."""

from __future__ import annotations

import json

import numpy as np
from conftest import EXAMPLES
from PIL import Image
from typer.testing import CliRunner

from flexmech.api.cli import app

ENV = {"COLUMNS": "200", "NO_COLOR": "1"}
SPIN = str(EXAMPLES / "spinning_rod_case2.json")


def test_simulate_prints_writes_and_draws(tmp_path):
    out = tmp_path / "run.json"
    result = CliRunner().invoke(
        app,
        [
            "simulate",
            SPIN,
            "--until",
            "2",
            "--step",
            "0.01",
            "--json",
            str(out),
            "--plot",
            str(tmp_path / "run.png"),
            "--animation",
            str(tmp_path / "run.gif"),
            "--snapshots",
            str(tmp_path / "shapes.svg"),
        ],
        env=ENV,
    )
    assert result.exit_code == 0, result.output
    assert "finished at t = 2 s, 200 steps" in result.output and "elements.rod.elongation" in result.output
    report = json.loads(out.read_text())
    assert report["status"] == "finished" and report["times"][-1] == 2.0
    # the hub follows Eq. 4.1: psi = 6/15 (t^2/2 + (15/2pi)^2 (cos(2 pi t/15) - 1)) before T_s
    t = np.array(report["times"])
    expected = 6 / 15 * (t**2 / 2 + (15 / (2 * np.pi)) ** 2 * (np.cos(2 * np.pi * t / 15) - 1))
    np.testing.assert_allclose(report["outputs"]["bodies.hub.angle"], expected, rtol=1e-9, atol=1e-12)
    assert Image.open(tmp_path / "run.png").size[0] > 400
    drawing = (tmp_path / "shapes.svg").read_text()
    assert drawing.count("t = ") == 6 and "t = 2.000 s" in drawing  # six times in the legend, the last one 2 s
    with Image.open(tmp_path / "run.gif") as movie:
        assert movie.n_frames == len(report["times"]) == 21  # every kept state (the document keeps every 10th)


def test_simulate_refuses_bad_options_naming_them(tmp_path):
    for arguments, words in [
        (["--animation", str(tmp_path / "a.avi")], "--animation: cannot tell the format of"),
        (["--snapshots", str(tmp_path / "a.txt")], "--snapshots: cannot tell the figure format of"),
        (["--step", "-1"], "/simulate/step: Input should be greater than 0"),
        (["--until", "0"], "/simulate/until: Input should be greater than 0"),
        (
            ["--scheme", "euler"],
            "/simulate/scheme: Input should be 'generalized_alpha', 'newmark', 'sdirk4', 'event_driven' or 'moreau'",
        ),
    ]:
        result = CliRunner().invoke(app, ["simulate", SPIN, *arguments], env=ENV)
        assert result.exit_code == 2, result.output
        assert words in result.output, result.output
