"""Contact laws from registries (models.contact.laws): a law of one's own is one class and one
registration line and then runs; each analysis refuses the laws it cannot take by name; and
documents with the old `impacts` section are converted by `flexmech upgrade`, refused by the
service with a 422 that says so, and once converted give seed 004's figures."""

from __future__ import annotations

import copy
import json
import math
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import httpx
import pytest
from impact_cases import EXAMPLES, csfh, parsed
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.api.client import Client
from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.models.contact.laws import NORMAL_LAWS, NormalLaw, register_normal_law
from flexmech.models.documents.upgrade import upgraded
from flexmech.service.analyses.base import AnalysisRequest
from flexmech.service.analyses.contact import CONTACT
from flexmech.service.impacts.event_driven import HYSTERESIS
from flexmech.service.impacts.run import run_impacts
from flexmech.service.solvers.newton import NewtonOptions

OLD = Path(__file__).resolve().parents[1] / "old_documents"
OLD_EXAMPLES = sorted(OLD.glob("*.json"))
MASS, STIFFNESS, SPEED = 10.0, 1e7, 0.5  # kg, N/m, m/s: the CSFH body thrown at its hole's wall


@dataclass(frozen=True)
class PureSpring(NormalLaw):
    """A law of this test's own: F = K q, elastic, for event_driven runs."""

    name: str = "pure_spring"
    analyses: frozenset[str] = frozenset({"event_driven"})
    summary: str = "F = K q"
    needs: tuple[str, ...] = ("stiffness",)

    def force(self, pair, q, rate, impact_speed):
        return pair.K * ca.fmax(q, 0.0)


@pytest.fixture
def own_law():
    register_normal_law(PureSpring())
    yield
    del NORMAL_LAWS["pure_spring"]


def _thrown(normal: dict) -> dict:
    """Scenario 6.1 without gravity: the body leaves the hole's centre at SPEED downwards."""
    doc = csfh("6.1", until=0.1)
    doc["gravity"] = [0, 0]
    doc["simulate"]["initial"]["hinge"] = {"displacement": [0, 0, 0], "velocity": [0, -SPEED, 0]}
    pair = doc["contacts"]["pairs"]["conjugate"]
    pair["normal"], pair["friction"] = normal, {"law": "none"}
    return doc


@pytest.mark.parametrize(
    "normal",
    [
        {"law": "pure_spring", "stiffness": STIFFNESS, "exponent": 1},
        {"law": "linear", "stiffness": STIFFNESS, "damping": 0},
    ],
    ids=["registered_here", "linear_undamped"],
)
def test_a_linear_spring_holds_the_body_for_half_its_period_and_returns_its_speed(own_law, normal):
    """F = K q on a translating mass: the contact lasts pi sqrt(m / K) exactly and the body
    leaves at the speed it came (its own law registered by this test, and the built-in
    linear spring-dashpot without damping)."""
    report = run_impacts(*parsed(_thrown(normal)))[1]
    first = report["impacts"][0]
    assert first["time"] == pytest.approx(0.02 / SPEED, rel=1e-9)
    beyond = HYSTERESIS * 0.02 / SPEED  # the contact ends a hair past the surface (event_driven's hysteresis)
    assert first["duration"] == pytest.approx(math.pi * math.sqrt(MASS / STIFFNESS) + beyond, rel=1e-9)
    assert first["rebound_ratio"] == pytest.approx(1.0, abs=1e-7)


def test_a_law_of_ones_own_is_listed_and_refused_where_it_does_not_belong(own_law):
    doc = _thrown({"law": "pure_spring", "stiffness": STIFFNESS})
    doc["simulate"].update(scheme="moreau", step=1e-5)
    with pytest.raises(MechanismError) as caught:
        run_impacts(*parsed(doc))
    assert caught.value.pointer == "/contacts/pairs/conjugate/normal/law"
    assert caught.value.problem == (
        "a moreau simulation does not take the normal law 'pure_spring' (it is for an "
        "event_driven simulation); it takes restitution"
    )
    doc["contacts"]["pairs"]["conjugate"]["normal"]["law"] = "pure_sprung"
    with pytest.raises(MechanismError, match="unknown normal law 'pure_sprung'; the normal laws are .*pure_spring"):
        run_impacts(*parsed(doc))


def test_a_quasi_static_solve_refuses_a_penalty_law_and_takes_the_unilateral_one():
    doc = json.loads((EXAMPLES / "gripper_jaw_contact.json").read_text())
    doc["contacts"]["objects"]["fixture"]["centre"][0] = 67.81
    doc["contacts"]["pairs"]["insertion"]["normal"] = {"law": "hertz", "stiffness": 1e6}
    request = AnalysisRequest(NewtonOptions(), {})
    with pytest.raises(MechanismError) as caught:
        CONTACT.run(compile_mechanism(load_document(doc)), request)
    assert caught.value.pointer == "/document/contacts/pairs/insertion/normal/law"  # the analysis names the request's
    assert "a quasi-static contact solve does not take the normal law 'hertz'" in caught.value.problem
    assert caught.value.problem.endswith("it takes unilateral")
    doc["contacts"]["pairs"]["insertion"]["normal"] = {"law": "unilateral"}
    written = CONTACT.run(compile_mechanism(load_document(doc)), request)
    default = json.loads((EXAMPLES / "gripper_jaw_contact.json").read_text())
    default["contacts"]["objects"]["fixture"]["centre"][0] = 67.81
    assert written["pairs"] == CONTACT.run(compile_mechanism(load_document(default)), request)["pairs"]


@pytest.mark.parametrize("old", OLD_EXAMPLES, ids=[path.stem for path in OLD_EXAMPLES])
def test_upgrade_converts_each_old_impact_example_to_the_shipped_one(old, tmp_path):
    target = tmp_path / old.name
    result = CliRunner().invoke(app, ["upgrade", str(old), "--output", str(target)])
    assert result.exit_code == 0, result.output
    assert "3 changes" in result.stderr and "/impacts/surfaces/hole -> /contacts/objects/hole" in result.stderr
    converted, shipped = json.loads(target.read_text()), json.loads((EXAMPLES / old.name).read_text())
    assert "impacts" not in converted and list(converted) == list(shipped)  # contacts where impacts was
    assert {**converted, "description": ""} == {**shipped, "description": ""}  # the shipped text names moreau's laws
    again = CliRunner().invoke(app, ["upgrade", str(target)])
    assert again.exit_code == 0 and json.loads(again.stdout) == converted and "0 changes" in again.stderr


def _upgraded_run(name: str, **simulate) -> dict:
    old = json.loads((OLD / name).read_text())
    old["simulate"].update(simulate)
    return run_impacts(*parsed(upgraded(old)[0]))[1]


def test_an_upgraded_moreau_document_gives_the_figures_of_an_independent_implementation():
    """Scenario 6.1 by Moreau-Jean (the old document with its scheme set to moreau, whose laws
    the upgrade turns into restitution impulses and Coulomb's friction): the first impulse
    and y(1 s) of the independent implementation, to 1e-9."""
    report = _upgraded_run("csfh_central_impact.json", scheme="moreau", step=1e-5)
    assert report["impacts"][0]["impulse"] == pytest.approx(14.578542899998768, rel=1e-9)
    assert report["coordinates"]["hinge.y"][-1] == pytest.approx(-0.018950829234239, rel=1e-9)
    event_driven = _upgraded_run("csfh_central_impact.json", until=0.1)
    assert event_driven["impacts"][0]["time"] == pytest.approx(math.sqrt(2 * 0.03 / 9.81), rel=1e-9)  # 0.0782062


def test_the_service_refuses_an_old_document_with_the_upgrade_command(api_server):
    old = json.loads((OLD / "csfh_central_impact.json").read_text())
    r = httpx.post(f"{api_server.url}/v1/solve", json={"document": old, "analysis": "simulate"}, timeout=60)
    assert r.status_code == 422, r.text
    error = r.json()["error"]
    assert error["pointer"] == "/document/impacts" and "flexmech upgrade DOC" in error["message"], error
    assert "/v1/documents/upgrade" in error["message"]
    with Client(api_server.url) as client:
        answer = client.upgrade_document(old)
    assert answer == {"document": upgraded(copy.deepcopy(old))[0], "changes": upgraded(old)[1]}
    r = httpx.post(
        f"{api_server.url}/v1/solve",
        json={"document": answer["document"], "analysis": "simulate", "simulate": {"until": 0.1}},
        timeout=60,
    )
    assert r.status_code == 200, r.text
    broken = {**old, "impacts": {**old["impacts"], "surfaces": {"pin": {"type": "square", "body": "hinge"}}}}
    error = httpx.post(f"{api_server.url}/v1/documents/upgrade", json={"document": broken}, timeout=60).json()["error"]
    assert error["pointer"] == "/document/impacts/surfaces/pin/type"
    assert "so a circle; it is a square" in error["message"]
