"""The client installs and works in an environment with only httpx and pydantic."""

from __future__ import annotations

import shutil
import subprocess
import textwrap
import venv
from pathlib import Path

from conftest import ACTUATION

REPO_API = Path(__file__).resolve().parents[2] / "api"

SCRIPT = textwrap.dedent("""
    import importlib.util, sys
    for heavy in ("casadi", "fastapi", "numpy", "sqlalchemy", "uvicorn"):
        assert importlib.util.find_spec(heavy) is None, heavy + " is installed"
    from flexmech.api.client import Client, FlexmechError
    with Client(sys.argv[1]) as c:
        answer = c.solve(example="gripper", target={"path": sys.argv[2], "output": "end_effector.x", "equals": 0})
        try:
            c.job("0" * 32)
        except FlexmechError as e:
            missing = e.status
    assert not {"casadi", "fastapi", "numpy"} & set(sys.modules), sorted(sys.modules)
    print(answer.target.value, missing)
""")


def test_client_installs_and_runs_without_casadi_or_fastapi(tmp_path, api_server):
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=True, system_site_packages=False).create(env_dir)
    python = env_dir / "bin" / "python"
    source = tmp_path / "client-src"
    shutil.copytree(REPO_API, source, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    install = subprocess.run(
        [str(python), "-m", "pip", "install", "--quiet", "--disable-pip-version-check", str(source)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert install.returncode == 0, install.stderr[-3000:]
    listed = subprocess.run([str(python), "-m", "pip", "list", "--format=freeze"], capture_output=True, text=True)
    names = {line.split("==")[0].lower() for line in listed.stdout.split()}
    assert {"httpx", "pydantic", "flexmech-client"} <= names and not {"casadi", "fastapi", "flexmech"} & names
    run = subprocess.run(
        [str(python), "-c", SCRIPT, api_server.url, ACTUATION],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    value, missing = run.stdout.split()
    assert abs(float(value) - 77.0346) < 1e-3 and missing == "404"
