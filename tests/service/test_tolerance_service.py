"""The tolerance analysis where users run it (issue 51, acceptance 2 and 5): over real HTTP as
/v1/solve answers it, as an analysis job on a Dask cluster (the same samples as a local run of
the same seed), and from the command line; bad tolerance data a 422 or a CLI error naming the
field."""

from __future__ import annotations

import json

import httpx
import pytest
from conftest import EXAMPLES
from typer.testing import CliRunner

import flexmech
from flexmech.api.cli import app
from flexmech.api.client import Client, FlexmechError
from flexmech.service.analysis import run_analysis
from flexmech.service.solvers.newton import NewtonOptions

DOCUMENT = json.loads((EXAMPLES / "gripper_tolerances.json").read_text())
OPTIONS = {"samples": 300, "seed": 9, "outputs": ["end_effector.x"]}
ENV = {"COLUMNS": "200", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "NO_COLOR": "1"}


@pytest.fixture(scope="module")
def local() -> dict:
    return run_analysis(flexmech.load(DOCUMENT), "tolerance", NewtonOptions(), OPTIONS)


def same_statistics(found: dict, expected: dict) -> None:
    assert found["samples"] == expected["samples"] and found["seed"] == expected["seed"]
    for name, entry in expected["responses"].items():
        for part in ("mean", "std", "min", "max"):
            assert found["responses"][name]["monte_carlo"][part] == pytest.approx(entry["monte_carlo"][part], rel=1e-10)
    assert found["yield"]["monte_carlo"] == expected["yield"]["monte_carlo"]
    assert [s["sample"] for s in found["yield"]["failing_samples"]] == [
        s["sample"] for s in expected["yield"]["failing_samples"]
    ]


def test_over_http_the_answer_is_the_local_report_and_bad_data_is_a_422(api_server, local):
    with Client(api_server.url) as client:
        answered = httpx.post(
            api_server.url + "/v1/solve", json={"document": DOCUMENT, "analysis": "tolerance", **OPTIONS}, timeout=120
        )
        bad = json.loads(json.dumps(DOCUMENT))
        bad["tolerances"]["fields"]["/sections/flexure/h"] = {"sigma": "2 um"}
        with pytest.raises(FlexmechError) as info:
            client.solve(document=bad, analysis="tolerance", samples=10)
    assert answered.status_code == 200, answered.text
    same_statistics(answered.json(), local)
    assert info.value.status == 422 and info.value.pointer == "/document/tolerances/fields/~1sections~1flexure~1h/sigma"
    assert "out of its range (above zero) with probability" in info.value.message


def test_an_analysis_job_on_dask_runs_the_local_samples(request, tmp_path, local):
    from conftest import make_deployment

    server = make_deployment("dask", request, tmp_path).start()
    try:
        with Client(server.url) as client:
            assert client.health().executor.startswith("Dask cluster")
            created = httpx.post(
                server.url + "/v1/analysis-jobs",
                json={"document": DOCUMENT, "analysis": "tolerance", **OPTIONS},
                timeout=120,
            )
            assert created.status_code in (200, 201, 202), created.text
            final = client.wait(created.json()["id"], timeout=300)
            assert final.status == "succeeded", final.error
            report = client.result(final.id).result["report"]
    finally:
        server.stop()
    same_statistics(report, local)


def test_the_command_runs_twice_and_names_a_bad_field(tmp_path, local):
    runner, document = CliRunner(), tmp_path / "etched.json"
    document.write_text(json.dumps(DOCUMENT))
    argv = ["tolerance", str(document), "--samples", "300", "--seed", "9", "--outputs", '["end_effector.x"]']
    for k in range(2):
        done = runner.invoke(
            app, [*argv, "--json", str(tmp_path / f"{k}.json"), "--plot", str(tmp_path / f"{k}.png")], env=ENV
        )
        assert done.exit_code == 0, done.output
        assert "yield:" in done.output and "contributions (first order)" in done.output
        same_statistics(json.loads((tmp_path / f"{k}.json").read_text()), local)
        assert (tmp_path / f"{k}.png").read_bytes()[:4] == b"\x89PNG"
    bad = json.loads(json.dumps(DOCUMENT))
    bad["tolerances"]["fields"] = {"/sections/flexure/width": {"sigma": "0.1 um"}}
    document.write_text(json.dumps(bad))
    done = runner.invoke(app, ["tolerance", str(document), "--samples", "10"], env=ENV)
    assert done.exit_code == 2
    assert "/tolerances/fields/~1sections~1flexure~1width" in done.output
    assert "not a numeric field of this mechanism" in done.output
