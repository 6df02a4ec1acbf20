"""What the workbench reads from the API besides the analyses themselves: the offers of a
document (which analyses and jobs apply, and why the others do not, in the words of their own
refusals), a key's recent jobs, and the units and load histories of simulation results."""

from __future__ import annotations

import time

import httpx
import numpy as np
import pytest
from conftest import EXAMPLES, sqlite_server

from flexmech.api.client import Client
from flexmech.models import compile_mechanism, load_document
from flexmech.service.analysis import run_analysis
from flexmech.service.offers import offers
from flexmech.service.solvers.newton import NewtonOptions

KEYS = ("workbench-first-key", "workbench-second-key")


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    server = sqlite_server(tmp_path_factory, "workbench-api", keys=KEYS)
    yield server
    server.stop()


def call(server, method: str, path: str, key: str = KEYS[0], **kwargs) -> httpx.Response:
    return httpx.request(method, server.url + path, headers={"X-API-Key": key}, timeout=120, **kwargs)


def offered(name: str) -> dict:
    return offers(compile_mechanism(load_document(EXAMPLES / f"{name}.json")))


def test_an_analysis_not_offered_is_refused_with_the_offers_reason():
    """The gripper's partial non-linear curved beams have no energy form: energy and contact
    are not offered, and running energy anyway is refused with the same words."""
    gripper = offered("gripper")
    assert gripper["analyses"]["equilibrium"] is None and gripper["jobs"]["sweep"] is None
    reason = gripper["analyses"]["energy"]
    assert reason.startswith("element 'a' (curved_beam) has no energy form: the partial_nonlinear")
    mech = compile_mechanism(load_document(EXAMPLES / "gripper.json"))
    with pytest.raises(Exception) as refused:
        run_analysis(mech, "energy", NewtonOptions())
    assert reason in str(refused.value)
    assert gripper["analyses"]["modes"] == "the mechanism has no mass: give a body a mass or a material a density"


def test_an_impact_document_is_offered_its_simulation_and_study_but_no_statics_or_simulation_job():
    impact = offered("csfh_central_impact")
    assert impact["analyses"]["simulate"] is None and impact["jobs"]["impact_study"] is None
    assert "no static state" in impact["analyses"]["equilibrium"]
    assert impact["jobs"]["simulation"].startswith("an event_driven impact simulation runs as the simulate analysis")


def test_massless_elements_keep_modes_but_not_link_dynamics():
    """The stage's blades carry no density: modes condense them (offered), link dynamics
    needs every element's mass (its simulate section is missing anyway)."""
    stage = offered("stage_frequency")
    assert stage["analyses"]["modes"] is None and stage["jobs"]["optimization"] is None
    assert stage["analyses"]["simulate"] is not None and stage["jobs"]["simulation"] is not None
    rod = offered("rod_free_vibration")
    assert rod["jobs"]["simulation"] is None and rod["analyses"]["modes"] is None
    assert rod["jobs"]["contact_path"] == "the document has no contact pairs"


def test_every_analysis_and_job_kind_has_an_offer(server):
    """The drawing of a document carries its offers, one per analysis and per job operation."""
    drawn = call(server, "POST", "/v1/drawings", json={"example": "gripper"}).json()
    served = {
        analysis["name"] for analysis in call(server, "GET", "/v1/analyses").json()
    }  # the server's registry, not this process' (tests register their own)
    assert set(drawn["offers"]["analyses"]) == served
    operations = {kind["route"] for kind in call(server, "GET", "/v1/job-kinds").json()}
    assert len(drawn["offers"]["jobs"]) == len(operations)
    assert set(drawn["offers"]["jobs"]) >= {"sweep", "optimization", "contact_path", "simulation", "impact_study"}


def test_a_key_lists_its_own_jobs_newest_first(server):
    def sweep(example: str, path: str) -> dict:
        return {"example": example, "parameters": [{"path": path, "values": [0.0, 1.0, 2.0]}]}

    first = call(server, "POST", "/v1/sweeps", json=sweep("gripper", "/loads/actuation/force/1"))
    second = call(server, "POST", "/v1/sweeps", json=sweep("cantilever", "/loads/F/force/1"))
    other = call(server, "POST", "/v1/sweeps", KEYS[1], json=sweep("gripper", "/loads/actuation/force/1"))
    assert first.status_code == second.status_code == other.status_code == 202, (first.text, second.text)
    listed = call(server, "GET", "/v1/jobs?limit=5").json()["jobs"]
    ids = [job["id"] for job in listed]
    assert ids[:2] == [second.json()["id"], first.json()["id"]]
    assert other.json()["id"] not in ids  # another key's job is never listed
    assert listed[1]["name"] == "MEMS gripper with curved-beam flexures (silicon)"
    assert {"status", "progress", "timings", "kind"} <= set(listed[0])
    assert call(server, "GET", "/v1/jobs?limit=0").status_code == 422
    with Client(server.url, api_key=KEYS[1]) as client:  # the client reads the same list
        assert [job.id for job in client.recent_jobs(limit=5).jobs] == [other.json()["id"]]


def _finished(server, job_id: str, seconds: float = 240) -> dict:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        status = call(server, "GET", f"/v1/jobs/{job_id}").json()
        if status["status"] in ("succeeded", "failed", "cancelled"):
            return call(server, "GET", f"/v1/jobs/{job_id}/result").json()
        time.sleep(0.25)
    raise AssertionError(f"job {job_id} did not finish in {seconds} s")


def test_a_simulation_job_gives_units_steps_and_the_drive_moment_in_time(server):
    """The four-bar's drive moment follows its table (0 at t = 0, 100 N*m from 0.2 s): the
    result carries it at every kept state, so the page draws the load each frame has."""
    posted = call(server, "POST", "/v1/simulations", json={"example": "four_bar_dynamics", "simulate": {"until": 0.3}})
    assert posted.status_code == 202, posted.text
    answer = _finished(server, posted.json()["id"])
    result = answer["result"]
    assert answer["status"] == "succeeded", result.get("message")
    drive = np.array(result["varying"]["values"]["/loads/drive/moment"])
    times = np.array(result["times"])
    assert len(drive) == len(times) and result["varying"]["units"]["/loads/drive/moment"] == "N*m"
    assert drive == pytest.approx(np.interp(times, [0, 0.2, 0.4, 0.6], [0, 100, 100, 0]), abs=1e-9)
    assert result["output_units"] and set(result["output_units"]) == set(result["outputs"])
    assert result["series_units"] and set(result["series_units"]) >= set(result["constraint_forces"])
    assert set(result["series_units"].values()) <= {"N", "N*m"}
    assert result["steps"] >= round(0.3 / 0.001) * 0.5  # adaptive: steps of the whole run, not the last window's


def test_an_impact_simulation_names_the_unit_of_every_series_and_event_field(server):
    report = call(
        server,
        "POST",
        "/v1/solve",
        json={"example": "csfh_asymmetric_impact", "analysis": "simulate", "simulate": {"until": 0.1}},
    ).json()
    units = report["series_units"]
    assert units["hinge.x"] == "m" and units["hinge.theta"] == "deg" and units["hinge.x.velocity"] == "m/s"
    for pair, fields in report["contacts"].items():
        assert all(f"{pair}.{field}" in units for field in fields), (pair, fields)
    assert units["conjugate.normal_force"] == "N" and units["conjugate.indentation"] == "m"
    assert report["impacts"], "the asymmetric impact strikes within 0.1 s"
    assert all(field in report["event_units"] for field in report["impacts"][0] if field != "pair")
    assert report["event_units"]["peak_force"] == "N" and report["event_units"]["impact_speed"] == "m/s"


def test_an_impact_study_names_the_unit_of_every_number(server):
    """Each studied field's change in the field's own unit, every other number by its name."""
    study = {
        "fields": [
            {"path": "/contacts/pairs/conjugate/normal/restitution", "step": 0.05},
            {"path": "/bodies/hinge/mass", "step": 0.01},
        ]
    }
    posted = call(
        server,
        "POST",
        "/v1/impact-studies",
        json={"example": "csfh_central_impact", "simulate": {"until": 0.05}, "study": study},
    )
    assert posted.status_code == 202, posted.text
    result = _finished(server, posted.json()["id"])["result"]
    units = {path: field["+"]["change_unit"] for path, field in result["fields"].items()}
    assert units == {"/contacts/pairs/conjugate/normal/restitution": "1", "/bodies/hinge/mass": "kg"}
    unnamed = []

    def walk(value, path: str, key: str, unit: str | None) -> None:
        if isinstance(value, dict):
            for name, inner in value.items():
                if name != "units" and not name.endswith("_unit"):
                    walk(inner, f"{path}/{name}", name, value.get(f"{name}_unit"))
        elif isinstance(value, int | float) and not isinstance(value, bool) and not (unit or result["units"].get(key)):
            unnamed.append(path)

    walk(result, "", "", None)
    assert unnamed == []
