"""The `flexmech` script leaves without Python's teardown (api.cli.leaving): what a command
printed and wrote is all there, its exit code is the documented one, and pint (imported without
its dask support, models.units) leaves dask importable for the sweeps that use it."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from conftest import EXAMPLES

from flexmech.api.cli.leaving import exit_code

ROOT = EXAMPLES.parent


def _flexmech(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "flexmech.api.cli", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=300,
        env={**os.environ, "COLUMNS": "200", "NO_COLOR": "1"},
    )


def test_a_command_leaves_everything_it_printed_and_wrote(tmp_path):
    out = tmp_path / "rod.json"
    done = _flexmech("simulate", str(EXAMPLES / "rod_free_vibration.json"), "--until", "0.05", "--json", str(out))
    assert done.returncode == 0, done.stderr
    # stdout is a pipe here (block-buffered): the table's last line arrives only if it was flushed
    assert "finished at t = 0.05 s, 50 steps" in done.stdout and done.stdout.rstrip().endswith("┘")
    report = json.loads(out.read_text())
    assert report["status"] == "finished" and report["times"][-1] == pytest.approx(0.05)


def test_a_bad_document_exits_with_2_and_says_why(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"bodies": ')
    done = _flexmech("solve", str(bad))
    assert done.returncode == 2
    assert done.stderr.startswith("error: ") and "bad.json" in done.stderr


def test_what_a_command_printed_is_flushed_before_the_exit():
    """print() into a pipe is block-buffered (PYTHONUNBUFFERED, which some machines set, is
    unset for the child): without the flush the lines would be lost."""
    buffered = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    script = (
        "import sys, api.cli.leaving as leaving\n"
        "def app():\n    print('\\n'.join(f'line {i}' for i in range(100)))\n    sys.exit(3)\n"
        "leaving.app = app\nleaving.main()\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, cwd=ROOT, timeout=120, env=buffered
    )
    assert done.returncode == 3, done.stderr
    assert done.stdout.splitlines() == [f"line {i}" for i in range(100)]


def test_exit_codes_are_pythons(capsys):
    assert exit_code(SystemExit(None)) == 0 and exit_code(SystemExit(3)) == 3
    assert exit_code(SystemExit("no such option")) == 1
    assert capsys.readouterr().err == "no such option\n"


def test_pint_without_dask_leaves_dask_importable():
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys; import flexmech.models.units as u; pint = u.pint_module(); "
            "assert 'dask' not in sys.modules and not pint.compat.HAS_DASK; "
            "import dask.bag; print(u.parse_unit('N*m/rad')[0], dask.bag.__name__)",
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["1.0", "dask.bag"]
