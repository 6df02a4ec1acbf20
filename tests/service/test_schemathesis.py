"""Generated requests against the OpenAPI schema (schemathesis, all phases, stateful included):
no request may produce a server error."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

from conftest import EXAMPLES, Deployment

MIN_REQUESTS = 500


def test_no_generated_request_gets_a_5xx(tmp_path):
    server = Deployment(
        "sqlite",
        {
            "FLEXMECH_DATA_DIR": str(tmp_path / "data"),
            "FLEXMECH_WORKERS": "2",
            "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
            "FLEXMECH_API_KEYS": "",
            "FLEXMECH_SOLVE_TIME_LIMIT": "2",
            "FLEXMECH_MAX_SWEEP_POINTS": "2000",
        },
        tmp_path,
    ).start(access_log=True)
    report = tmp_path / "schemathesis.json"
    st = shutil.which("schemathesis") or str(Path(sys.executable).parent / "schemathesis")
    try:
        run = subprocess.run(
            [
                st,
                "run",
                f"{server.url}/openapi.json",
                "--checks",
                "not_a_server_error",
                "--max-examples",
                "100",
                "--workers",
                "2",  # two requests at once: the server answers while it checks (and CI keeps its time)
                "--seed",
                "20261121",
                "--generation-database",
                "none",
                "--no-color",
                "--report",
                "json",
                "--report-json-path",
                str(report),
                "--request-timeout",
                "30",
            ],
            capture_output=True,
            text=True,
            timeout=600,
            cwd=tmp_path,
        )
        served = server.output(tail=None)
    finally:
        server.stop()
    summary = json.loads(report.read_text())
    assert run.returncode == 0 and not summary["failures"] and not summary["errors"], run.stdout[-3000:]
    assert summary["test_cases"]["generated"] >= MIN_REQUESTS
    # uvicorn's access log, independent of schemathesis' own count
    statuses = [int(s) for s in re.findall(r'"(?:GET|POST|DELETE|PUT|PATCH|HEAD|OPTIONS) [^"]*" (\d{3})', served)]
    assert len(statuses) >= MIN_REQUESTS
    assert not [s for s in statuses if s >= 500]
    assert "Traceback" not in served
    print(
        f"schemathesis: {summary['test_cases']['generated']} test cases, {len(statuses)} requests served, "
        f"statuses {sorted(set(statuses))}"
    )
