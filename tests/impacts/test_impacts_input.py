"""Impact simulations: bad input names the field (Python, HTTP 422, CLI), and the simulate
analysis answers over real HTTP."""

from __future__ import annotations

import copy
import json
import math

import httpx
import pytest
from impact_cases import csfh, parsed
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.models import MechanismError
from flexmech.service.impacts.run import run_impacts


def _broken(change) -> dict:
    doc = copy.deepcopy(csfh("6.3", until=0.05))
    change(doc)
    return doc


def _pair(doc):
    return doc["contacts"]["pairs"]["conjugate"]


BAD = [
    (lambda d: d["bodies"]["hinge"].pop("mass"), "/bodies/hinge/mass", "moves and has no mass"),
    (
        lambda d: d["simulate"]["initial"].update(hinge={"displacement": [0, -0.03, 0]}),
        "/simulate/initial/hinge",
        "the start state penetrates: pair 'conjugate' overlaps by 0.01 m",
    ),
    (
        lambda d: _pair(d)["normal"].update(restitution=1.2),
        "/contacts/pairs/conjugate/normal/restitution",
        "must be in (0, 1], got 1.2",
    ),
    (
        lambda d: _pair(d)["normal"].update(restitution=0.0),
        "/contacts/pairs/conjugate/normal/restitution",
        "must be in (0, 1], got 0",
    ),
    (
        lambda d: _pair(d)["friction"].update(sliding=-0.05),
        "/contacts/pairs/conjugate/friction/sliding",
        "a friction coefficient must not be negative, got -0.05",
    ),
    (
        lambda d: _pair(d).update(object="hol"),
        "/contacts/pairs/conjugate/object",
        "unknown object 'hol' (objects: hole)",
    ),
    (
        lambda d: d["contacts"]["objects"]["hole"].update(radius=0.18),
        "/contacts/objects/hole/radius",
        "the clearance of pair 'conjugate' (hole radius 0.18 m minus pin radius 0.18 m) must be positive, got 0 m",
    ),
    (
        lambda d: _pair(d)["friction"].update(law="coulomb"),
        "/contacts/pairs/conjugate/friction/law",
        "an event_driven simulation does not take the friction law 'coulomb' (it is for a quasi-static contact solve, "
        "a moreau simulation); it takes none or ambrosio",
    ),
    (
        lambda d: _pair(d)["normal"].update(law="unilateral"),
        "/contacts/pairs/conjugate/normal/law",
        "an event_driven simulation does not take the normal law 'unilateral' (it is for a quasi-static contact "
        "solve); it takes hertz or hunt_crossley or lankarani_nikravesh or flores or lna_esdu or linear",
    ),
    (
        lambda d: d["simulate"].update(scheme="moreau", step=1e-5),
        "/contacts/pairs/conjugate/normal/law",
        "a moreau simulation does not take the normal law 'lankarani_nikravesh' (it is for an event_driven "
        "simulation, a newmark or generalized_alpha simulation (and the equilibrium solve)); it takes restitution",
    ),
    (
        lambda d: _pair(d)["normal"].update(law="lankarani_nikravsh"),
        "/contacts/pairs/conjugate/normal/law",
        "unknown normal law 'lankarani_nikravsh'; the normal laws are unilateral, restitution, hertz",
    ),
    (
        lambda d: d["simulate"]["initial"].update(frame={"displacement": [0, 0.001, 0]}),
        "/simulate/initial/frame",
        "body 'frame' is fixed",
    ),
]


@pytest.mark.parametrize("change,pointer,words", BAD)
def test_bad_impact_input_names_the_field(change, pointer, words):
    document, spec = parsed(_broken(change))
    with pytest.raises(MechanismError) as caught:
        run_impacts(document, spec)
    assert caught.value.pointer == pointer
    assert words in caught.value.problem


def test_the_simulate_analysis_answers_impacts_over_http_and_refuses_bad_fields_with_422(api_server):
    r = httpx.post(
        f"{api_server.url}/v1/solve", json={"document": csfh("6.1", until=0.1), "analysis": "simulate"}, timeout=120
    )
    assert r.status_code == 200, r.text
    first = r.json()["impacts"][0]
    assert first["time"] == pytest.approx(math.sqrt(2 * 0.03 / 9.81), rel=1e-9)
    for change, pointer, words in BAD[1:3]:
        r = httpx.post(
            f"{api_server.url}/v1/solve", json={"document": _broken(change), "analysis": "simulate"}, timeout=120
        )
        assert r.status_code == 422, r.text
        error = r.json()["error"]
        assert error["pointer"] == pointer and words in error["message"], error


def test_the_cli_runs_an_impact_example_and_names_bad_fields(tmp_path):
    runner = CliRunner()
    doc = tmp_path / "csfh.json"
    doc.write_text(json.dumps(csfh("6.1", until=0.1)))
    out = tmp_path / "r.json"
    result = runner.invoke(app, ["simulate", str(doc), "--json", str(out), "--plot", str(tmp_path / "r.png")])
    assert result.exit_code == 0, result.output
    assert "0.0782062" in result.output
    assert (tmp_path / "r.png").stat().st_size > 10_000
    assert json.loads(out.read_text())["impacts"][0]["impact_speed"] == pytest.approx(math.sqrt(2 * 9.81 * 0.03))
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(_broken(BAD[6][0])))
    result = runner.invoke(app, ["simulate", str(bad)])
    assert result.exit_code != 0
    assert "/contacts/objects/hole/radius" in result.output and "must be positive" in result.output


def test_the_impact_study_ranks_the_clearance_above_the_inertia(api_server):
    """Seed 004 Table 4 in numbers: the pin radius (the clearance) changes the motion from the
    first impact; a 0.001 kg m^2 inertia change barely does. Run as a job on the pool."""
    from flexmech.api.client import Client

    with Client(api_server.url) as client:
        job = client.impact_study(
            example="csfh",
            simulate={"until": 0.3},
            study={
                "fields": [
                    {"path": "/contacts/sites/pin/radius", "step": 0.001},
                    {"path": "/bodies/hinge/inertia", "step": 0.001},
                ]
            },
        )
        assert job.progress.total == 5
        final = client.wait(job.id, timeout=300)
        assert final.status == "succeeded", final
        result = client.result(job.id).result
    radius = result["fields"]["/contacts/sites/pin/radius"]
    inertia = result["fields"]["/bodies/hinge/inertia"]
    assert result["ranking"][0]["path"] == "/contacts/sites/pin/radius"
    # a 1 mm smaller pin falls 1 mm further: the first impact, and the departure, come later
    early = radius["+"]["influence"]["hinge.y"]["departure"]
    assert early is not None and early < 0.08
    assert inertia["+"]["influence"]["hinge.y"]["rms"] < radius["+"]["influence"]["hinge.y"]["rms"] / 10
    bad = httpx.post(
        f"{api_server.url}/v1/impact-studies",
        json={"example": "csfh", "study": {"fields": [{"path": "/contacts/sites/pin/colour", "step": 1}]}},
    )
    assert bad.status_code == 422 and bad.json()["error"]["pointer"] == "/study/fields/0/path", bad.text


def test_one_response_bounds_the_states_it_keeps():
    from flexmech.service.impacts.run import run_impacts as run_bounded

    document, spec = parsed(csfh("6.1", scheme="moreau", step=1e-5, until=0.1))
    _, report = run_bounded(document, spec, max_kept=1000)
    assert report["steps"] == 10_000 and "kept one state in 11 of 10000 steps" in report["message"]
    impact = report["impacts"][0]
    assert 910 < len(report["times"]) <= 1000 + 4 * len(report["impacts"])
    assert impact["time"] in report["times"]  # the states around the impact are among the kept ones
    document, spec = parsed(csfh("6.1", until=0.5))
    _, report = run_bounded(document, spec, max_kept=50)
    assert len(report["times"]) <= 51 + 2 * len(report["events"]) and report["times"][-1] == pytest.approx(0.5)
    assert "kept one state in" in report["message"]


def test_the_default_report_of_a_long_moreau_run_is_bounded():
    """10^5 steps: about max_points states (under 2 MB of JSON), every impact among them with
    its peak force, and each contact's onset and separation as events."""
    document, spec = parsed(csfh("6.3", scheme="moreau", step=1e-5, until=1.0))
    _, report = run_impacts(document, spec)
    assert report["steps"] == 100_000 and len(report["impacts"]) >= 10
    assert spec.max_points <= len(report["times"]) <= spec.max_points + 4 * len(report["impacts"]) + 1
    assert len(json.dumps(report)) < 2_000_000
    for hit in report["impacts"]:
        assert hit["peak_force"] == pytest.approx(hit["impulse"] / 1e-5, rel=1e-12)  # one step's impulse
        assert hit["time"] in report["times"]
    contacts = [e for e in report["events"] if e["kind"] == "contact"]
    separations = [e for e in report["events"] if e["kind"] == "separation"]
    assert len(contacts) == len(separations) >= len(report["impacts"])
    assert all(s["time"] > c["time"] for c, s in zip(contacts, separations))


def test_a_moreau_run_whose_states_would_not_fit_is_refused_before_it_starts():
    """The states a report needs are held in memory: 20 s of 1e-5 s steps (2 million, within
    the step limit) would take about 780 MiB at their peak."""
    from flexmech.service.analyses.simulate import SYNC_IMPACT_BYTES
    from flexmech.service.impacts.run import held_bytes, model_of

    document, spec = parsed(csfh("6.3", scheme="moreau", step=1e-5, until=20.0))
    needed = held_bytes(model_of(document, spec), spec)
    assert needed == 3 * 8 * 2_000_001 * 17  # t, q and v of one body, 5 works; a pair's 5 numbers
    with pytest.raises(MechanismError) as caught:
        run_impacts(document, spec, max_bytes=SYNC_IMPACT_BYTES)
    assert caught.value.pointer == "/simulate/until"
    assert caught.value.problem.startswith(
        f"20 s of moreau steps of 1e-05 s would hold about {needed / 2**20:.0f} MiB of "
        "states, over the 192 MiB one run may take"
    )


def test_an_impact_study_is_costed_before_it_runs(api_server):
    fields = [{"path": "/bodies/hinge/mass", "step": 0.001 * (k + 1)} for k in range(8)]
    r = httpx.post(
        f"{api_server.url}/v1/impact-studies",
        json={
            "example": "csfh",
            "simulate": {"scheme": "moreau", "step": 1e-9, "until": 10.0},
            "study": {"fields": fields},
        },
    )
    assert r.status_code == 422, r.text
    assert r.json()["error"]["pointer"] == "/simulate/step" and "over the limit" in r.json()["error"]["message"]
