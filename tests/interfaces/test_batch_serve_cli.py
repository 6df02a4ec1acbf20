"""`flexmech batch` (a folder of documents to a folder of results) and `flexmech serve`."""

from __future__ import annotations

import json
import shutil
import sys
import time

import httpx
import pytest
from conftest import EXAMPLES
from servers import Process, free_port
from typer.testing import CliRunner

from flexmech.api.cli import app

ENV = {"COLUMNS": "200", "NO_COLOR": "1"}


def test_batch_writes_every_result_and_fails_if_one_failed(tmp_path, gripper_dict):
    docs = tmp_path / "in"
    docs.mkdir()
    shutil.copy(EXAMPLES / "gripper.json", docs / "gripper.json")  # declares a sweep until closed
    plain = {k: v for k, v in gripper_dict.items() if k != "sweep"}
    (docs / "at_50.json").write_text(json.dumps(plain))
    broken = json.loads(json.dumps(plain))
    broken["elements"]["a"]["radius"] = 0
    (docs / "broken.json").write_text(json.dumps(broken))
    (docs / "notes.txt").write_text("not a document")
    out = tmp_path / "out"

    result = CliRunner().invoke(app, ["batch", str(docs), "--out", str(out)], env=ENV)

    assert result.exit_code == 1, result.output
    assert "broken.json: /elements/a/radius: must be positive" in result.output
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["documents"], summary["succeeded"], summary["failed"]) == (3, 2, 1)
    assert sorted(p.name for p in out.iterdir()) == ["at_50.json", "broken.json", "gripper.json", "summary.json"]
    swept = json.loads((out / "gripper.json").read_text())
    assert swept["analysis"] == "sweep" and swept["target"]["value"] == pytest.approx(77.0346, abs=1e-3)
    assert len(swept["sweep"]["values"]) == 101
    solved = json.loads((out / "at_50.json").read_text())
    assert solved["status"] == "converged" and solved["outputs"]["end_effector.x"] > 0
    assert json.loads((out / "broken.json").read_text())["status"] == "error"


def test_batch_of_a_folder_without_documents_is_an_error(tmp_path):
    result = CliRunner().invoke(app, ["batch", str(tmp_path), "--out", str(tmp_path / "o")], env=ENV)
    assert result.exit_code == 2
    assert f"error: DIRECTORY: no documents (*.json, *.yaml) in '{tmp_path}'" in result.stderr


def test_serve_answers_health_on_its_port(tmp_path):
    port = free_port()
    env = {"FLEXMECH_PORT": str(port), "FLEXMECH_DATA_DIR": str(tmp_path), "FLEXMECH_WORKERS": "1"}
    server = Process([sys.executable, "-m", "flexmech.api.cli", "serve"], tmp_path / "serve.log", env)
    try:
        for _ in range(300):
            try:
                health = httpx.get(f"http://127.0.0.1:{port}/v1/health", timeout=1).json()
                break
            except httpx.HTTPError:
                assert server.running(), server.output()
                time.sleep(0.1)
        else:
            raise AssertionError(server.output())
    finally:
        server.stop()
    assert health["status"] == "ok" and health["database"] == "sqlite"
    assert (tmp_path / "flexmech.db").exists()


def test_serve_names_a_bad_setting(tmp_path):
    result = CliRunner().invoke(app, ["serve"], env={**ENV, "FLEXMECH_MAX_ELEMENTS": "0"})
    assert result.exit_code == 2
    assert "error: FLEXMECH_MAX_ELEMENTS: Input should be greater than or equal to 1" in result.stderr
