"""The README's `flexmech upgrade` line: the shipped document of an older shape (an `impacts`
section) is refused as it is, naming the section and the command, and its upgrade is a document
of today's shape that compiles."""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.models import compile_mechanism, load_document

OLD = Path(__file__).resolve().parents[2] / "examples" / "old_documents" / "csfh_before_contacts.json"


def test_the_shipped_old_document_is_refused_as_it_is_and_upgrades(tmp_path):
    runner = CliRunner()
    refused = runner.invoke(app, ["solve", str(OLD)], env={"NO_COLOR": "1", "COLUMNS": "200"})
    assert refused.exit_code == 2 and "flexmech upgrade DOC" in refused.output and "/impacts" in refused.output
    upgraded = tmp_path / "csfh.json"
    done = runner.invoke(app, ["upgrade", str(OLD), "-o", str(upgraded)], env={"NO_COLOR": "1"})
    assert done.exit_code == 0, done.output
    document = json.loads(upgraded.read_text())
    assert "impacts" not in document and set(document["contacts"]["pairs"]) == {"conjugate"}
    assert compile_mechanism(load_document(document)).document.contacts is not None
