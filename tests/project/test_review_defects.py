"""Defects found on review (issue 11), each pinned by a test that failed before its fix."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import get_args

import numpy as np
import pytest
from conftest import ACTUATION, EXAMPLES
from typer.testing import CliRunner

from flexmech.api.client import Client
from flexmech.models import MODELS, compile_mechanism, load_document

ROOT = Path(__file__).resolve().parents[2]
ENV = {"COLUMNS": "200", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "NO_COLOR": "1"}


@pytest.fixture(scope="module")
def client(api_server):
    with Client(api_server.url) as c:
        yield c


def test_an_optimal_start_is_not_a_failed_point(client):
    """The store counted every point whose status was not 'converged' as failed, so each
    optimal start of an optimize job showed up in progress.failed_points."""
    problem = json.loads((EXAMPLES / "grasper_shape.json").read_text())["optimize"]
    job = client.optimize(example="grasper_shape", problem={**problem, "starts": 2})
    final = client.wait(job.id, timeout=300)
    assert final.status == "succeeded"
    assert [s["status"] for s in client.result(job.id).result["starts"]] == ["optimal", "optimal"]
    assert final.progress.done == 2
    assert final.progress.failed_points == 0


def test_the_exact_model_over_http_and_one_list_of_models(client):
    """POST /v1/solve refused "model": "exact" although the CLI took it: the client's schema
    kept its own list of models."""
    from flexmech.api.schemas import Model

    assert tuple(get_args(Model)) == MODELS
    answer = client.solve(
        example="gripper", model="exact", target={"path": ACTUATION, "output": "end_effector.x", "equals": 0}
    )
    assert answer.target.status == "converged"
    assert answer.target.value == pytest.approx(69.857, abs=1e-3)  # README: exact 69.86 uN


def test_residual_norm_means_one_thing_in_a_solve_and_in_a_sweep_point():
    """A sweep point's residual_norm was the nondimensional norm of every row (moments and
    link rows included) divided by the force scale, while /v1/solve reported the largest
    unbalanced force; both were labelled with the force unit."""
    from flexmech.service.analysis import Limits, compile_request, equilibrium_report, newton_options
    from flexmech.service.jobs.kinds import kind_named

    document = json.loads((EXAMPLES / "gripper.json").read_text())
    options = {"max_iterations": 1, "line_search": False}
    mech = compile_request(document, overrides={ACTUATION: 400.0})
    report = equilibrium_report(mech, newton_options(options))
    assert report["status"] == "not_converged"
    spec = {
        "document": document,
        "options": options,
        "overrides": {},
        "parameters": [{"path": ACTUATION, "values": [400.0]}],
    }
    kind = kind_named("sweep")
    plan = kind.prepare(spec, Limits()).meta
    [(_, point)] = kind.run(spec, kind.tasks(spec, plan, {}, chunk_size=8)[0])
    assert point["status"] == "not_converged"
    assert point["residual_norm"] == pytest.approx(report["residual_norm"], rel=1e-12)
    assert point["residual_moment"] == pytest.approx(report["residual_moment"], rel=1e-12)


def test_body_mass_and_inertia_are_not_ignored():
    """Body mass and inertia were accepted and silently ignored: now they form the mass
    matrix, and under gravity the mass is a weight the supports carry."""
    document = {
        "units": {"length": "m", "force": "N", "mass": "kg"},
        "gravity": [0, -9.81],
        "bodies": {
            "ground": {"fixed": True, "position": [0, 0]},
            "block": {"position": [0.5, 0], "mass": 2.0, "inertia": 0.25, "center_of_mass": [0.1, 0.0]},
        },
        "elements": {
            "k": {"type": "spring", "kind": "torsional", "from": "ground", "to": "block", "stiffness": 1e6},
            "pin": {"type": "pin", "from": "ground", "to": "block", "at": [0.5, 0]},
        },
        "outputs": {"support": {"type": "reaction", "body": "ground"}},
    }
    mech = compile_mechanism(load_document(document))
    from flexmech.service.solvers.equilibrium import solve_equilibrium

    result = solve_equilibrium(mech)
    assert result.converged
    outputs = result.outputs()
    assert outputs["support.Fy"] == pytest.approx(2.0 * 9.81, rel=1e-9)
    # The weight at the centre of mass, 0.1 m from the pin, twists the torsional spring.
    assert outputs["elements.k.M"] == pytest.approx(-2.0 * 9.81 * 0.1, rel=1e-6)
    from flexmech.service.solvers.inertia import mass_matrix

    coordinates, M = mass_matrix(mech)
    assert coordinates == ["block.x", "block.y", "block.angle"]
    np.testing.assert_allclose(M, [[2.0, 0, 0], [0, 2.0, 0.2], [0, 0.2, 0.25]], rtol=1e-12, atol=1e-15)


def test_material_density_is_not_ignored():
    """A link's material density was accepted and ignored: under gravity a light cantilever
    sags by its own weight, w L^4 / (8 EI) for small deflections."""
    E, b, h, L, rho, g = 200e9, 0.01, 0.002, 0.5, 7800.0, 9.81
    document = {
        "units": {"length": "m", "force": "N", "stress": "Pa", "mass": "kg"},
        "gravity": [0, -g],
        "materials": {"steel": {"E": E, "density": rho}},
        "sections": {"strip": {"b": b, "h": h}},
        "bodies": {"wall": {"fixed": True, "position": [0, 0]}, "tip": {"position": [L, 0]}},
        "elements": {
            "beam": {"type": "link", "from": "wall", "to": "tip", "length": L, "material": "steel", "section": "strip"}
        },
    }
    mech = compile_mechanism(load_document(document))
    from flexmech.service.solvers.equilibrium import solve_equilibrium

    result = solve_equilibrium(mech)
    outputs = result.outputs()
    w = rho * b * h * g
    EI = E * b * h**3 / 12
    assert outputs["elements.beam.mass"] == pytest.approx(rho * b * h * L, rel=1e-12)
    assert outputs["bodies.tip.y"] == pytest.approx(-w * L**4 / (8 * EI), rel=2e-3)  # small-deflection theory
    assert outputs["reactions.wall.Fy"] == pytest.approx(w * L, rel=1e-9)


def test_cli_stiffness_json_is_the_service_report(tmp_path):
    """`flexmech solve --stiffness --json` lacked `symmetric`, so it differed from /v1/solve."""
    from flexmech.api.cli import app
    from flexmech.service.analysis import compile_request, equilibrium_report, newton_options

    out = tmp_path / "k.json"
    result = CliRunner().invoke(
        app, ["solve", str(EXAMPLES / "gripper.json"), "--stiffness", "--json", str(out)], env=ENV
    )
    assert result.exit_code == 0, result.output
    cli = json.loads(out.read_text())["stiffness"]
    mech = compile_request(json.loads((EXAMPLES / "gripper.json").read_text()))
    service = equilibrium_report(mech, newton_options(None), stiffness=True)["stiffness"]
    assert set(cli) == set(service)
    assert cli["symmetric"] == service["symmetric"]
    np.testing.assert_allclose(cli["K"], service["K"], rtol=1e-12)


def test_the_gripper_benchmark_runs_as_the_readme_says():
    """`python3 benchmarks/gripper.py` failed with an ImportError: benchmarks/service.py, on
    sys.path first when run as a script, hid the service package."""
    done = subprocess.run(
        [sys.executable, "benchmarks/gripper.py", "--repeats", "1", "--sweep-repeats", "1"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "ImportError" not in done.stderr
    assert "scipy/this" in done.stdout
