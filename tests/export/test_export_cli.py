"""`flexmech export DOC --c DIR` (issue 29): what it writes and says, and its option errors,
each naming the option or field."""

from __future__ import annotations

import json

from conftest import EXAMPLES
from typer.testing import CliRunner

from flexmech.api.cli import app

ENV = {"COLUMNS": "200", "NO_COLOR": "1"}


def _invoke(*args: str):
    return CliRunner().invoke(app, list(args), env=ENV)


def test_export_writes_the_library_and_names_its_inputs_and_outputs(tmp_path):
    folder = tmp_path / "c"
    done = _invoke(
        "export",
        str(EXAMPLES / "gripper.json"),
        "--c",
        str(folder),
        "--model",
        "linear",
        "--range",
        "/loads/actuation/force/1=-100:100",
        "--json",
        str(tmp_path / "m.json"),
    )
    assert done.exit_code == 0, done.output
    assert "actuation_force_y" in done.output and "/loads/actuation/force/1" in done.output
    assert f"build it with: make -C {folder}" in done.output
    names = {p.name for p in folder.iterdir()}
    assert {
        "gripper.c",
        "gripper.h",
        "gripper_kernels.c",
        "Makefile",
        "CMakeLists.txt",
        "main.c",
        "bench.c",
        "check.c",
        "loader.py",
        "manifest.json",
    } <= names
    manifest = json.loads((tmp_path / "m.json").read_text())["manifest"]
    assert manifest == json.loads((folder / "manifest.json").read_text())
    force = next(i for i in manifest["inputs"] if i["name"] == "actuation_force_y")
    assert (force["low"], force["high"], force["unit"]) == (-100.0, 100.0, "uN")
    header = (folder / "gripper.h").read_text()
    assert "#define GRIPPER_IN_ACTUATION_FORCE_Y 1 /* /loads/actuation/force/1 [uN], range [-100.0, 100.0] */" in header
    assert "#define GRIPPER_OUT_END_EFFECTOR_X 0 /* end_effector.x [mm] */" in header


def test_export_option_errors_name_what_is_wrong(tmp_path):
    doc = str(EXAMPLES / "gripper.json")
    bad_range = _invoke("export", doc, "--c", str(tmp_path / "a"), "--range", "/loads/actuation/force/1=5")
    assert (
        bad_range.exit_code == 2
        and "--range: expected POINTER=LOW:HIGH, got '/loads/actuation/force/1=5'" in bad_range.output
    )
    half_target = _invoke("export", doc, "--c", str(tmp_path / "b"), "--target", "end_effector.x=0")
    assert half_target.exit_code == 2 and "give both --target OUTPUT=VALUE and --by POINTER" in half_target.output
    bad_output = _invoke("export", doc, "--c", str(tmp_path / "c"), "--output", "end_effector.q")
    assert (
        bad_output.exit_code == 2
        and "/outputs/0" in bad_output.output
        and "unknown output 'end_effector.q'" in bad_output.output
    )
    bad_contact = _invoke("export", doc, "--c", str(tmp_path / "d"), "--contact", "maybe")
    assert bad_contact.exit_code == 2 and "unknown choice 'maybe'" in bad_contact.output
    assert not any((tmp_path / x).exists() for x in "abcd")


def test_a_contact_documents_export_chooses_its_contact_outputs(tmp_path):
    doc = str(EXAMPLES / "gripper_jaw_contact.json")
    chosen = _invoke("export", doc, "--c", str(tmp_path / "jaw"), "--contact-output", "contacts.insertion.normal_force")
    assert chosen.exit_code == 0, chosen.output
    manifest = json.loads((tmp_path / "jaw" / "manifest.json").read_text())
    assert manifest["contact"]["outputs"] == [{"output": "contacts.insertion.normal_force", "unit": "N"}]
    header = (tmp_path / "jaw" / "gripper_jaw_contact.h").read_text()
    assert (
        "#define GRIPPER_JAW_CONTACT_CONTACT_INSERTION_NORMAL_FORCE 0 /* contacts.insertion.normal_force [N] */"
        in header
    )
    wrong = _invoke("export", doc, "--c", str(tmp_path / "bad"), "--contact-output", "contacts.insertion.grip")
    assert wrong.exit_code == 2 and "/contact_outputs" in wrong.output and "'contacts.insertion.grip'" in wrong.output


def test_a_build_past_its_time_ends_every_process_it_started(monkeypatch, tmp_path):
    """--build runs make in a process group of its own: at its time limit the whole group is
    killed (here a shell and the sleeper it started, standing for make and its compilers)."""
    import os
    import subprocess

    import pytest

    from flexmech.api.cli import export as export_command

    monkeypatch.setattr(export_command, "BUILD_SECONDS", 0.5)
    marker = tmp_path / "pid"
    with pytest.raises(subprocess.TimeoutExpired):
        export_command._run_in_own_group(["sh", "-c", f"sleep 60 & echo $! > {marker}; wait"])
    sleeper = int(marker.read_text())
    try:
        os.kill(sleeper, 0)
        state = open(f"/proc/{sleeper}/stat").read().split()[2]
    except (ProcessLookupError, FileNotFoundError):
        state = "gone"
    assert state in ("gone", "Z"), f"the sleeper survived its group's kill (state {state})"
