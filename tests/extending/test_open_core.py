"""The seams of the open core: graphs saved on disk and loaded by a new process, the one IPOPT
module, and the analyses registry through /v1/solve, the sweep job and the CLI."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import httpx
import numpy as np
import pytest
from conftest import EXAMPLES
from mechanisms import chain
from typer.testing import CliRunner

from flexmech.api.client import Client
from flexmech.models import compile_mechanism, load_document
from flexmech.service.solvers.energy import minimize_energy

ROOT = Path(__file__).resolve().parents[2]
ENV = {"COLUMNS": "200", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "NO_COLOR": "1"}

# In a fresh process: count graph builds, solve gripper_exact, print the count and the outputs.
PROBE = """
import json, sys
import flexmech.models.graph.assembly as assembly
built = []
build = assembly.build_functions
assembly.build_functions = lambda structure: built.append(1) or build(structure)
from flexmech.models import compile_mechanism, load_document
from flexmech.service.solvers.equilibrium import solve_equilibrium
result = solve_equilibrium(compile_mechanism(load_document(sys.argv[1])))
print(json.dumps({"built": len(built), "status": result.status, "outputs": result.outputs()}))
"""


def _fresh_process(cache: Path) -> dict:
    done = subprocess.run(
        [sys.executable, "-c", PROBE, str(EXAMPLES / "gripper_exact.json")],
        cwd=ROOT,
        env={"PATH": "/usr/bin:/bin", "FLEXMECH_CACHE_DIR": str(cache), "HOME": str(cache)},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_new_process_loads_the_graphs_it_built_before(tmp_path):
    first = _fresh_process(tmp_path)
    second = _fresh_process(tmp_path)
    assert (first["built"], second["built"]) == (1, 0)
    assert first["status"] == second["status"] == "converged"
    assert second["outputs"] == first["outputs"]
    # A damaged file is rebuilt, not trusted.
    (saved,) = (tmp_path / "graphs").glob("*/residual_and_tangent.casadi")
    saved.write_bytes(b"not a CasADi function")
    third = _fresh_process(tmp_path)
    assert third["built"] == 1 and third["outputs"] == first["outputs"]


def test_ipopt_options_are_allowlisted_and_solvers_built_once():
    from flexmech.service.solvers import ipopt

    with pytest.raises(
        ipopt.IpoptOptionError,
        match="linear_solver: value 'ma57' is not allowed "
        r"\(the wheel's IPOPT has mumps and spral\)",
    ):
        ipopt.checked_options({"linear_solver": "ma57"})
    with pytest.raises(ipopt.IpoptOptionError, match="^derivative_test: not an IPOPT option flexmech sets"):
        ipopt.checked_options({"derivative_test": "second-order"})
    with pytest.raises(ipopt.IpoptOptionError, match="^max_iter: expected a int"):
        ipopt.checked_options({"max_iter": 1.5})
    built = []

    def problem():
        import casadi as ca

        built.append(1)
        x = ca.SX.sym("x")
        return {"x": x, "f": (x - 2) ** 2}

    first = ipopt.nlp_solver("test_square", "key", problem, {"tol": 1e-12})
    again = ipopt.nlp_solver("test_square", "key", problem, {"tol": 1e-12})
    assert first is again and built == [1]
    outcome = ipopt.solve(first, x0=0.0)
    assert outcome.status == "optimal" and outcome.x[0] == pytest.approx(2.0, abs=1e-9)


def test_bounded_equilibrium_reuses_its_solver():
    from flexmech.service.solvers import ipopt
    from flexmech.service.solvers.equilibrium import solve_bounded

    mech = compile_mechanism(load_document(EXAMPLES / "cantilever.json"))
    first = solve_bounded(mech, {"tip.x": (None, 200.0)})
    count = ipopt.cached_solvers()
    second = solve_bounded(mech.with_values({"/loads/F/force/1": 10.0}), {"tip.x": (None, 200.0)})
    assert first.converged and second.converged
    assert ipopt.cached_solvers() == count


@pytest.fixture(scope="module")
def client(api_server):
    with Client(api_server.url) as c:
        yield c


def test_the_energy_analysis_over_http_equals_the_core(client):
    answer = client.solve(document=chain(), analysis="energy")
    core = minimize_energy(compile_mechanism(load_document(chain())))
    assert answer.analysis == "energy" and answer.status == "converged"
    for name, value in core.outputs().items():
        assert answer.outputs[name] == pytest.approx(value, rel=1e-9, abs=1e-12), name


def test_an_unknown_analysis_names_the_field_and_the_choices(api_server):
    r = httpx.post(api_server.url + "/v1/solve", json={"example": "gripper", "analysis": "simulation"})
    assert r.status_code == 422
    error = r.json()["error"]
    assert error["pointer"] == "/analysis"
    assert error["message"] == (
        "/analysis: unknown analysis 'simulation' (analyses: equilibrium, linearization, "
        "trace, inverse, energy, contact, simulate, modes, frequency_response, tolerance)"
    )
    schema = httpx.get(api_server.url + "/openapi.json").json()["components"]["schemas"]
    assert list(schema["SolveRequest"]["discriminator"]["mapping"]) == [
        "equilibrium",
        "linearization",
        "trace",
        "inverse",
        "energy",
        "contact",
        "simulate",
        "modes",
        "frequency_response",
        "tolerance",
    ]
    assert schema["TraceSolve"]["properties"]["analysis"]["const"] == "trace"
    assert "trace" in schema["TraceSolve"]["properties"] and "trace" not in schema["EquilibriumSolve"]["properties"]
    assert schema["SweepRequest"]["properties"]["analysis"]["enum"] == ["equilibrium", "energy"]


def test_a_sweep_of_energy_minima_follows_newton(client):
    values = [0.0, 1.0, 2.0]
    job = client.sweep(
        document=chain(),
        analysis="energy",
        continuation="/loads/pull/force/0",
        parameters=[{"path": "/loads/pull/force/0", "values": values}],
        outputs=["bodies.b1.x"],
    )
    assert client.wait(job.id, timeout=120).status == "succeeded"
    result = client.result(job.id).result
    assert result.analysis == "energy"
    from flexmech.service.solvers.equilibrium import solve_equilibrium

    mech = compile_mechanism(load_document(chain()))
    for point, value in zip(result.points, values):
        newton = solve_equilibrium(mech.with_values({"/loads/pull/force/0": value})).outputs()
        assert point.status == "converged"
        assert point.outputs["bodies.b1.x"] == pytest.approx(newton["bodies.b1.x"], abs=1e-8)


def test_the_cli_runs_any_analysis_of_the_registry(tmp_path):
    from flexmech.api.cli import app

    path, out = tmp_path / "chain.json", tmp_path / "energy.json"
    path.write_text(json.dumps(chain()))
    result = CliRunner().invoke(app, ["solve", str(path), "--analysis", "energy", "--json", str(out)], env=ENV)
    assert result.exit_code == 0, result.output
    report = json.loads(out.read_text())
    assert report["analysis"] == "energy" and report["status"] == "converged"
    newton = CliRunner().invoke(app, ["solve", str(path), "--json", str(tmp_path / "newton.json")], env=ENV)
    assert newton.exit_code == 0
    expected = json.loads((tmp_path / "newton.json").read_text())["outputs"]
    np.testing.assert_allclose([report["outputs"][k] for k in expected], list(expected.values()), atol=1e-8)
    bad = CliRunner().invoke(app, ["solve", str(path), "--analysis", "simulation"], env=ENV)
    assert bad.exit_code == 2
    assert bad.stderr.strip().startswith("error: --analysis: unknown analysis 'simulation' (analyses: ")
