"""Exact derivatives of an event-driven impact run's end state (service.impacts.state_sensitivity)
against central differences of the same run, made by changing the document itself."""

from __future__ import annotations

import json
from pathlib import Path

import httpx
import numpy as np
import pytest
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.models import MechanismError
from flexmech.models.documents.document import MechanismDocument
from flexmech.models.documents.simulation_spec import SimulateSpec
from flexmech.service.impacts.run import run_impacts
from flexmech.service.impacts.study import variant

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
PAIR = "/contacts/pairs/conjugate"
STIFFNESS = f"{PAIR}/normal/stiffness"
# scenario 6.3 (a flexure, Lankarani-Nikravesh impacts, Ambrosio friction) over its first three
# contacts: the law's stiffness and restitution, the friction, a mass and the flexure's modulus
FIELDS = [
    STIFFNESS,
    f"{PAIR}/normal/restitution",
    f"{PAIR}/friction/sliding",
    "/bodies/hinge/mass",
    "/materials/hinge/E",
]
RELATIVE_STEP = 1e-5  # of each field: the differences agree to 6e-7 here (7.7e-6 at 1e-4, their truncation)


def _csfh(until: float) -> dict:
    """Scenario 6.3 with the law's stiffness written as its number (N/m^1.5, Table 2), so the
    document holds every field differentiated."""
    doc = json.loads((EXAMPLES / "csfh.json").read_text())
    doc["contacts"]["pairs"]["conjugate"]["normal"]["stiffness"] = 2.2656e9
    doc["simulate"]["until"] = until
    return doc


def _run(doc: dict) -> dict:
    return run_impacts(MechanismDocument.model_validate(doc), SimulateSpec.model_validate(doc["simulate"]))[1]


def _end_state(report: dict) -> np.ndarray:
    return np.array([values[-1] for part in ("coordinates", "velocities") for values in report[part].values()])


def _field(doc: dict, pointer: str) -> float:
    node = doc
    for part in pointer[1:].split("/"):
        node = node[part]
    return node


def test_end_state_derivatives_equal_central_differences_of_the_document():
    """Each derivative (document units: m, deg and per second, per the field's own unit) equals
    the central difference of two runs of the changed document to 1e-5 of the largest
    component, and asking for them leaves the motion as it was."""
    doc = _csfh(0.28)
    plain = _run(doc)
    doc["simulate"]["sensitivities"] = FIELDS
    report = _run(doc)
    assert report["coordinates"] == plain["coordinates"] and report["events"] == plain["events"]
    assert sum(event["kind"] == "contact" for event in report["events"]) >= 3
    sensitivities = report["sensitivities"]
    assert sensitivities["time"] == pytest.approx(0.28, abs=1e-15) and sensitivities["warnings"] == []
    assert sensitivities["fields"][STIFFNESS]["unit"] == "N/m^1.5"
    assert sensitivities["fields"]["/materials/hinge/E"]["unit"] == "GPa"
    for pointer in FIELDS:
        found = sensitivities["fields"][pointer]
        exact = np.array([values[name] for values in (found["coordinates"], found["velocities"]) for name in values])
        step = RELATIVE_STEP * abs(_field(doc, pointer))
        up, down = (_end_state(_run(variant(doc, pointer, sign * step))) for sign in (1, -1))
        differences = (up - down) / (2 * step)
        assert np.abs(differences).max() > 0, pointer
        assert np.abs(exact - differences).max() <= 1e-5 * np.abs(differences).max(), (pointer, exact, differences)


def test_a_grazing_contact_is_named_as_one_whose_time_has_no_derivative():
    """The pin starts touching the hole's bottom at rest: gravity begins a contact at zero speed."""
    doc = json.loads((EXAMPLES / "csfh_central_impact.json").read_text())
    doc["simulate"].update(
        until=0.02, sensitivities=["/bodies/hinge/mass"], initial={"hinge": {"displacement": [0, -0.02, 0]}}
    )
    warnings = _run(doc)["sensitivities"]["warnings"]
    assert len(warnings) == 1 and "pair 'conjugate'" in warnings[0] and "begins grazing" in warnings[0]


def test_sensitivities_of_other_schemes_and_unknown_fields_are_refused_by_name():
    doc = json.loads((EXAMPLES / "csfh_central_impact.json").read_text())
    with pytest.raises(ValueError, match="sensitivities are those of an event_driven run.*the moreau scheme has none"):
        SimulateSpec.model_validate({**doc["simulate"], "scheme": "moreau", "sensitivities": ["/bodies/hinge/mass"]})
    doc["simulate"].update(until=0.01, sensitivities=["bodies/hinge/mas"])
    with pytest.raises(MechanismError, match="did you mean /bodies/hinge/mass") as error:
        _run(doc)
    assert error.value.pointer == "/simulate/sensitivities/0"


def test_the_command_line_prints_the_derivatives_it_writes(tmp_path):
    out = tmp_path / "run.json"
    result = CliRunner().invoke(
        app,
        [
            "simulate",
            str(EXAMPLES / "csfh_central_impact.json"),
            "--until",
            "0.1",
            "--sensitivity",
            f"{PAIR}/normal/restitution",
            "--json",
            str(out),
        ],
    )
    assert result.exit_code == 0, result.output
    written = json.loads(out.read_text())["sensitivities"]["fields"][f"{PAIR}/normal/restitution"]
    assert written["coordinates"]["hinge.y"] > 0  # a livelier rebound ends higher
    assert "d (state at t = 0.1 s) / d field" in result.stdout
    assert f"{written['coordinates']['hinge.y']:.6g}" in result.stdout


def test_the_service_answers_sensitivities_and_refuses_them_for_moreau_with_422(api_server):
    doc = json.loads((EXAMPLES / "csfh_central_impact.json").read_text())
    local = run_impacts(
        MechanismDocument.model_validate(doc),
        SimulateSpec.model_validate({**doc["simulate"], "until": 0.1, "sensitivities": ["/bodies/hinge/mass"]}),
    )[1]["sensitivities"]
    asked = {"until": 0.1, "sensitivities": ["/bodies/hinge/mass"]}
    r = httpx.post(
        f"{api_server.url}/v1/solve", json={"document": doc, "analysis": "simulate", "simulate": asked}, timeout=120
    )
    assert r.status_code == 200, r.text
    assert r.json()["sensitivities"]["fields"] == local["fields"]
    r = httpx.post(
        f"{api_server.url}/v1/solve",
        json={"document": doc, "analysis": "simulate", "simulate": {**asked, "scheme": "moreau"}},
        timeout=120,
    )
    assert r.status_code == 422, r.text
    error = r.json()["error"]
    assert error["pointer"] == "/simulate/sensitivities" and "event_driven" in error["message"], error


def test_the_damping_of_the_simulate_section_is_a_number_too():
    """d (end state) / d alpha of the mass-proportional damping, against central differences."""
    doc = _csfh(0.15)
    doc["simulate"].update(damping=2.0, sensitivities=["/simulate/damping"])
    found = _run(doc)["sensitivities"]["fields"]["/simulate/damping"]
    assert found["unit"] == "1/s"
    exact = np.array([values[name] for values in (found["coordinates"], found["velocities"]) for name in values])
    doc["simulate"]["sensitivities"] = []
    step = 1e-5
    up, down = (_end_state(_run(variant(doc, "/simulate/damping", sign * step))) for sign in (1, -1))
    differences = (up - down) / (2 * step)
    assert np.abs(exact - differences).max() <= 1e-5 * np.abs(differences).max(), (exact, differences)
    doc["simulate"].update(histories={"/gravity/1": "-9.81"}, sensitivities=["/gravity/1"])
    with pytest.raises(MechanismError, match="'/gravity/1' is not a number of this run") as caught:
        _run(doc)
    assert caught.value.pointer == "/simulate/sensitivities/0"
