"""`flexmech batch`: the output folder is never the input folder, results of documents sharing
a stem do not overwrite each other or the summary, an unreadable document is one failed row,
and each document is run through the analysis it declares (optimize, inverse, sweep,
equilibrium)."""

from __future__ import annotations

import io
import json
import shutil
from pathlib import Path

import pytest
import yaml
from conftest import EXAMPLES
from rich.console import Console
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.api.cli.batch import print_summary
from flexmech.models import load_document
from flexmech.service.batch import declared_analysis, result_names, run_batch, succeeded

ENV = {"COLUMNS": "200", "NO_COLOR": "1"}


@pytest.fixture
def cantilever() -> dict:
    """The thesis cantilever without its sweep: one equilibrium, tip x = 85.956 mm."""
    document = json.loads((EXAMPLES / "cantilever.json").read_text())
    del document["sweep"]
    return document


def batch(docs: Path, out: Path | str):
    return CliRunner().invoke(app, ["batch", str(docs), "--out", str(out)], env=ENV)


def summary_of(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text())


# --- 1. --out is never the input folder ------------------------------------------------------
@pytest.mark.parametrize("how", ["same path", "dot", "symlink", "through a missing folder"])
def test_batch_refuses_out_that_is_the_input_folder(tmp_path, cantilever, how):
    docs = tmp_path / "in"
    docs.mkdir()
    text = json.dumps(cantilever)
    (docs / "beam.json").write_text(text)
    out = {
        "same path": docs,
        "dot": docs / ".",
        "symlink": tmp_path / "link",
        "through a missing folder": docs / "missing" / "..",
    }[how]
    if how == "symlink":
        out.symlink_to(docs, target_is_directory=True)

    result = batch(docs, out)

    assert result.exit_code == 2, result.output
    assert result.stderr.startswith("error: --out: ") and "is the input folder" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
    assert sorted(p.name for p in docs.iterdir()) == ["beam.json"]
    assert (docs / "beam.json").read_text() == text


def test_run_batch_refuses_the_input_folder_as_out(tmp_path, cantilever):
    (tmp_path / "beam.json").write_text(json.dumps(cantilever))
    with pytest.raises(ValueError, match="is the input folder"):
        run_batch(tmp_path, tmp_path / "x" / "..")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["beam.json"]


def test_batch_may_write_into_a_folder_inside_the_input_folder(tmp_path, cantilever):
    (tmp_path / "beam.json").write_text(json.dumps(cantilever))

    result = batch(tmp_path, tmp_path / "results")

    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in (tmp_path / "results").iterdir()) == ["beam.json", "summary.json"]
    assert json.loads((tmp_path / "results" / "beam.json").read_text())["outputs"]["tip.x"] == pytest.approx(
        85.9561617, abs=1e-4
    )


# --- 2. result files never overwrite each other or the summary --------------------------------
def test_batch_names_results_by_file_name_when_stems_clash(tmp_path, cantilever):
    docs = tmp_path / "in"
    docs.mkdir()
    (docs / "a.json").write_text(json.dumps({**cantilever, "name": "a from JSON"}))
    (docs / "a.yaml").write_text(yaml.safe_dump({**cantilever, "name": "a from YAML"}))
    (docs / "summary.json").write_text(json.dumps({**cantilever, "name": "called summary"}))
    (docs / "b.json").write_text(json.dumps({**cantilever, "name": "b"}))
    out = tmp_path / "out"

    result = batch(docs, out)

    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in out.iterdir()) == [
        "a.json.json",
        "a.yaml.json",
        "b.json",
        "summary.json",
        "summary.json.json",
    ]
    summary = summary_of(out)
    assert (summary["documents"], summary["succeeded"], summary["failed"]) == (4, 4, 0)
    results = {row["document"]: row["result"] for row in summary["results"]}
    assert results == {
        "a.json": "a.json.json",
        "a.yaml": "a.yaml.json",
        "b.json": "b.json",
        "summary.json": "summary.json.json",
    }
    names = {"a.json": "a from JSON", "a.yaml": "a from YAML", "b.json": "b", "summary.json": "called summary"}
    for document, file in results.items():
        written = json.loads((out / file).read_text())
        assert (written["document"], written["name"]) == (document, names[document])


def test_result_names_stay_distinct_when_a_file_name_is_another_stem():
    names = result_names([Path(n) for n in ("a.json", "a.yaml", "a.yaml.json", "a.yaml.json.json", "b.yml")])
    assert {p.name: n for p, n in names.items()} == {
        "a.json": "a.json.json",
        "a.yaml": "a.yaml.json",
        "a.yaml.json": "a.yaml.json.json",
        "a.yaml.json.json": "a.yaml.json.json.json",
        "b.yml": "b.json",
    }
    assert {n for n in result_names([Path("A.json"), Path("a.yaml"), Path("Summary.yml")]).values()} == {
        "A.json.json",
        "a.yaml.json",
        "Summary.yml.json",
    }


# --- 3. an unreadable document is one failed row -----------------------------------------------
def test_batch_reports_unreadable_documents_and_runs_the_others(tmp_path, cantilever):
    docs = tmp_path / "in"
    docs.mkdir()
    (docs / "beam.json").write_text(json.dumps(cantilever))
    (docs / "latin1.json").write_bytes(b'{"name": "caf\xe9"}')
    (docs / "deep.json").write_text("[" * 100_000 + "]" * 100_000)
    (docs / "deep.yaml").write_text("[" * 100_000 + "]" * 100_000)
    (docs / "list.yaml").write_text("- a\n- b\n")
    out = tmp_path / "out"

    result = batch(docs, out)

    assert result.exit_code == 1 and isinstance(result.exception, SystemExit), result.output
    summary = summary_of(out)
    assert (summary["documents"], summary["succeeded"], summary["failed"]) == (5, 1, 4)
    rows = {row["document"]: row for row in summary["results"]}
    assert rows["beam.json"]["status"] == "converged"
    assert rows["latin1.json"]["message"] == f"document: {docs / 'latin1.json'} is not UTF-8 text (byte 13)"
    assert rows["deep.json"]["message"] == f"document: {docs / 'deep.json'} nests deeper than 64 levels"
    assert rows["deep.yaml"]["message"] == f"document: {docs / 'deep.yaml'} nests deeper than 64 levels"
    assert rows["list.yaml"]["message"] == "document: a mechanism document must be a JSON object"
    for name in ("latin1", "deep", "list"):
        assert rows[f"{name}.{'yaml' if name == 'list' else 'json'}"]["status"] == "error"
    assert json.loads((out / "latin1.json").read_text())["status"] == "error"
    assert "latin1.json: document: " in result.output and "Traceback" not in result.output


# --- 4. each document's own analysis ----------------------------------------------------------
def test_batch_runs_the_optimization_and_the_inverse_documents_declare(tmp_path, cantilever):
    docs = tmp_path / "in"
    docs.mkdir()
    shutil.copy(EXAMPLES / "grasper_shape.json", docs / "grasper_shape.json")
    shutil.copy(EXAMPLES / "inverse_four_bar.json", docs / "inverse_four_bar.json")
    (docs / "beam.json").write_text(json.dumps(cantilever))
    out = tmp_path / "out"

    result = batch(docs, out)

    assert result.exit_code == 0, result.output
    summary = summary_of(out)
    rows = {row["document"]: (row["analysis"], row["status"]) for row in summary["results"]}
    assert rows == {
        "beam.json": ("equilibrium", "converged"),
        "grasper_shape.json": ("optimize", "optimal"),
        "inverse_four_bar.json": ("inverse", "converged"),
    }
    assert (summary["succeeded"], summary["failed"]) == (3, 0)
    optimum = json.loads((out / "grasper_shape.json").read_text())
    assert optimum["constraints"][0]["value"] == pytest.approx(0.0508, abs=1e-6)  # the ground's x, in m
    assert set(optimum["design"]) == {"/elements/link/length", "/elements/link/shape/coefficients/0"}
    inverse = json.loads((out / "inverse_four_bar.json").read_text())
    assert inverse["loads"]["/loads/F/force/0"] == pytest.approx(35.904, abs=1e-3)
    assert inverse["load_units"]["/loads/F/force/0"] == "N"
    assert set(inverse["links"]) == {"L1", "L2", "L3"} and set(inverse["bodies"]) == {"J1", "J2", "J3", "J4"}
    assert "grasper_shape.json:" not in result.output  # no failure line


def test_the_declared_analysis_goes_by_precedence(gripper_dict):
    grasper = json.loads((EXAMPLES / "grasper_shape.json").read_text())
    four_bar = json.loads((EXAMPLES / "inverse_four_bar.json").read_text())
    document = {**gripper_dict, "optimize": grasper["optimize"], "inverse": four_bar["inverse"]}
    assert "sweep" in document
    expected = ["optimize", "inverse", "sweep", "equilibrium"]
    for section, analysis in zip(["optimize", "inverse", "sweep", None], expected):
        assert declared_analysis(load_document(document)) == analysis
        document.pop(section, None)


def test_success_depends_on_the_analysis():
    assert succeeded("optimize", "optimal") and succeeded("optimize", "acceptable")
    assert not succeeded("optimize", "infeasible") and not succeeded("optimize", "converged")
    assert all(succeeded(a, "converged") for a in ("equilibrium", "sweep", "inverse"))
    assert not succeeded("equilibrium", "optimal") and not succeeded(None, "error")


def test_the_table_colours_an_optimal_optimization_green():
    rows = [
        {
            "document": "o.json",
            "result": "o.json",
            "analysis": "optimize",
            "status": "optimal",
            "message": "",
            "seconds": 1.0,
        },
        {
            "document": "e.json",
            "result": "e.json",
            "analysis": "equilibrium",
            "status": "not_converged",
            "message": "no convergence",
            "seconds": 1.0,
        },
    ]
    console = Console(file=io.StringIO(), force_terminal=True, color_system="standard", width=200)

    print_summary(console, {"documents": 2, "results": rows}, Path("out"))

    text = console.file.getvalue()
    assert "\x1b[32moptimal" in text and "\x1b[31mnot_converged" in text
    assert "o.json:" not in text and "e.json:" in text and "no convergence" in text
