"""An analysis of the test's own, registered from this file alone (its options model, its result
model and its report, then one line `ANALYSES.register(...)`), is served by /v1/solve and in
/openapi.json, is a command of `flexmech` with its flags, a method of the Python client with
its docstring, a choice of `flexmech batch --analysis`, and a form of the workbench (checked in
Chromium), and runs through each of them. Likewise a job kind of its own (its options, its
typed spec and the contract of service.jobs.base, then `register_job_kind(...)`): a route, a
client method, a choice of the workbench's Run menu.

The server imports this module as a plugin (FLEXMECH_PLUGINS=tests.extending.test_own_analysis), so its
top-level imports are the package's only; the test helpers are imported inside the tests.

The analysis: the stiffness a force on one body meets along x or y at the undeformed state,
every other coordinate free: 1 / C_ii of the compliance C = K_T^-1. For a straight clamped
link of length L with axial strain, the tip's is 3 EI / L^3 across it and EA / L along it."""

from __future__ import annotations

import json
from typing import Literal

import numpy as np
import pytest
from pydantic import ConfigDict, Field

from flexmech.models import Mechanism, MechanismError
from flexmech.service.analyses import ANALYSES, Analysis, AnalysisOptions, AnalysisRequest, AnalysisResult
from flexmech.service.jobs.base import JSON, JobOptions, Plan, StoredJob, read_spec
from flexmech.service.jobs.kinds import register_job_kind
from flexmech.service.requests import Limits, compile_request
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.stiffness import tangent_stiffness

E, B, H, L = 2e11, 0.01, 0.001, 0.1  # Pa, m, m, m
ACROSS = 3 * E * (B * H**3 / 12) / L**3  # 500 N/m
ALONG = E * B * H / L  # 2e7 N/m


class BodyStiffnessOptions(AnalysisOptions):
    body: str = Field(description="the body the force pushes", examples=["tip"])
    direction: Literal["x", "y"] = Field("y", description="the force's direction")


class BodyStiffnessReport(AnalysisResult):
    stiffness: float = Field(description="force per displacement of the body, the other coordinates free")
    stiffness_unit: str


class BodyStiffness(Analysis):
    name = "body_stiffness"
    summary = "The stiffness a force on one body meets along x or y at the undeformed state, all else free"
    Options = BodyStiffnessOptions
    Result = BodyStiffnessReport

    def report(self, mech: Mechanism, newton: NewtonOptions, options: BodyStiffnessOptions) -> dict:
        kt = tangent_stiffness(mech, None)
        coordinate = f"{options.body}.{options.direction}"
        if coordinate not in kt.coordinates:
            raise MechanismError(
                "/body",
                f"'{options.body}' has no free coordinate {options.direction} (free: {', '.join(kt.coordinates)})",
            )
        k = kt.coordinates.index(coordinate)
        compliance = np.linalg.inv(np.asarray(kt.K, dtype=float))
        return {
            "analysis": self.name,
            "name": mech.document.name,
            "status": "converged",
            "message": "",
            "stiffness": float(1 / compliance[k, k]),
            "stiffness_unit": f"{mech.doc_unit('force')}/{mech.doc_unit('length')}",
        }


ANALYSES.register(BodyStiffness())


class StiffnessMapOptions(JobOptions):
    body: str = Field(description="the body the force pushes")
    path: str = Field(pattern=r"^/", description="the numeric field varied")
    values: list[float] = Field(min_length=1, max_length=64, description="its values, document units")


class StiffnessMapSpec(StoredJob, StiffnessMapOptions):
    model_config = ConfigDict(extra="ignore")


class StiffnessMap:
    """A job: the body's stiffness across (body_stiffness) at each value of a numeric field."""

    name, paged, Options = "stiffness_map", False, StiffnessMapOptions
    route, operation_id, request_name = "stiffness-maps", "create_stiffness_map", "StiffnessMapRequest"
    title, summary = "Start a stiffness map", "A job: a body's stiffness at each value of a numeric field."
    description, examples = "One point per value.", []

    def prepare(self, stored: JSON, limits: Limits) -> Plan:
        spec = read_spec(StiffnessMapSpec, stored)
        compile_request(spec.document, spec.model, spec.overrides, limits).parameter_index(spec.path)
        return Plan(len(spec.values), {})

    def tasks(self, stored: JSON, plan: JSON, finished, chunk_size: int) -> list[JSON]:
        count = len(read_spec(StiffnessMapSpec, stored).values)
        return [{"indices": [k]} for k in range(count) if k not in finished]

    def follow_up(self, stored, plan, task, finished, chunk_size):
        return []

    def run(self, stored: JSON, task: JSON) -> list[tuple[int, JSON]]:
        spec = read_spec(StiffnessMapSpec, stored)
        mech = compile_request(spec.document, spec.model, spec.overrides)
        points = []
        for k in task["indices"]:
            at = mech.with_values({spec.path: spec.values[k]})
            report = BodyStiffness().run(at, AnalysisRequest(given={"body": spec.body}))
            points.append((k, {"value": spec.values[k], "stiffness": report["stiffness"]}))
        return points

    def failed(self, point: JSON) -> bool:
        return False

    def result(self, stored: JSON, plan: JSON, finished) -> JSON:
        return {"points": [finished[k] for k in sorted(finished)]}


register_job_kind(StiffnessMap())

CLAMPED_LINK = {
    "name": "clamped link",
    "units": {"length": "m", "force": "N", "stress": "Pa", "angle": "rad"},
    "materials": {"steel": {"E": E}},
    "sections": {"strip": {"b": B, "h": H}},
    "bodies": {"wall": {"fixed": True, "position": [0, 0]}, "tip": {"position": [L, 0]}},
    "elements": {
        "link": {
            "type": "link",
            "from": "wall",
            "to": "tip",
            "length": L,
            "material": "steel",
            "section": "strip",
            "axial": True,
        }
    },
}
PLUGIN = {"FLEXMECH_PLUGINS": "tests.extending.test_own_analysis"}


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    from conftest import sqlite_server

    server = sqlite_server(tmp_path_factory, "own-analysis", workers=1, **PLUGIN)
    yield server
    server.stop()


def test_the_analysis_is_in_the_openapi_schema_and_the_analyses_list(server):
    import httpx

    schema = httpx.get(server.url + "/openapi.json").json()["components"]["schemas"]
    assert schema["SolveRequest"]["discriminator"]["mapping"]["body_stiffness"].endswith("/BodyStiffnessSolve")
    fields = schema["BodyStiffnessSolve"]["properties"]
    assert fields["body"]["description"] == "the body the force pushes" and fields["direction"]["enum"] == ["x", "y"]
    assert "stiffness_unit" in schema["BodyStiffnessResult"]["properties"]
    listed = {a["name"]: a for a in httpx.get(server.url + "/v1/analyses").json()}
    assert listed["body_stiffness"]["options"]["required"] == ["body"]


def test_it_runs_through_the_client_as_a_documented_method(server):
    from flexmech.api.client import Client, FlexmechError

    with Client(server.url) as client:
        method = client.analyze.body_stiffness
        assert "body (string, required): the body the force pushes" in method.__doc__
        across = method(document=CLAMPED_LINK, body="tip")
        along = method(document=CLAMPED_LINK, body="tip", direction="x")
        assert across.analysis == "body_stiffness" and across.stiffness_unit == "N/m"
        assert across.stiffness == pytest.approx(ACROSS, rel=1e-6)
        assert along.stiffness == pytest.approx(ALONG, rel=1e-6)
        with pytest.raises(FlexmechError) as bad:
            method(document=CLAMPED_LINK, body="wall")
        assert bad.value.status == 422 and bad.value.pointer == "/body"
        with pytest.raises(FlexmechError) as wrong:
            client.solve(document=CLAMPED_LINK, analysis="body_stiffness", body="tip", stiffness=True)
        assert wrong.value.pointer == "/stiffness"
        assert (
            "unknown field 'stiffness' for the body_stiffness analysis (the equilibrium and energy analysis"
            in wrong.value.message
        )


def test_it_is_a_command_with_its_flags(tmp_path):
    from typer.testing import CliRunner

    from flexmech.api.cli import app

    document = tmp_path / "link.json"
    document.write_text(json.dumps(CLAMPED_LINK))
    listing = CliRunner().invoke(app, ["--help"], env={"COLUMNS": "200"})
    assert "body-stiffness" in listing.output and "The stiffness a force on one body meets" in listing.output
    flags = CliRunner().invoke(app, ["body-stiffness", "--help"], env={"COLUMNS": "200"})
    assert "--body" in flags.output and "the body the force pushes" in flags.output and "(x | y)" in flags.output
    out = tmp_path / "report.json"
    ran = CliRunner().invoke(
        app,
        ["body-stiffness", str(document), "--body", "tip", "--direction", "x", "--json", str(out)],
        env={"COLUMNS": "200"},
    )
    assert ran.exit_code == 0, ran.output
    assert json.loads(out.read_text())["stiffness"] == pytest.approx(ALONG, rel=1e-6)
    assert "stiffness: 20 MN/m" in ran.output  # 2e7 N/m in its display unit (service.display)
    refused = CliRunner().invoke(app, ["body-stiffness", str(document), "--body", "tip", "--direction", "z"])
    assert refused.exit_code == 2 and refused.stderr.startswith("error: --direction: Input should be 'x' or 'y'")


def test_it_runs_in_batch(tmp_path):
    from flexmech.service.batch import Chosen, run_batch

    folder = tmp_path / "in"
    folder.mkdir()
    (folder / "link.json").write_text(json.dumps(CLAMPED_LINK))
    analysis = ANALYSES.named("body_stiffness")
    summary = run_batch(folder, tmp_path / "out", chosen=Chosen(analysis, analysis.options_of({"body": "tip"})))
    assert summary["succeeded"] == 1 and summary["results"][0]["analysis"] == "body_stiffness"
    result = json.loads((tmp_path / "out" / "link.json").read_text())
    assert result["stiffness"] == pytest.approx(ACROSS, rel=1e-6)


def test_a_job_kind_of_its_own_is_a_route_and_a_client_method(server):
    import httpx

    from flexmech.api.client import Client

    paths = httpx.get(server.url + "/openapi.json").json()["paths"]
    assert paths["/v1/stiffness-maps"]["post"]["operationId"] == "create_stiffness_map"
    heights = [0.001, 0.002]
    with Client(server.url) as client:
        assert "values (array, required): its values, document units" in client.jobs.stiffness_map.__doc__
        job = client.jobs.stiffness_map(document=CLAMPED_LINK, body="tip", path="/sections/strip/h", values=heights)
        assert client.wait(job.id, timeout=120).status == "succeeded"
        points = client.result(job.id).result["points"]
    # 3 E I / L^3 with I = b h^3 / 12: twice the height, eight times the stiffness
    assert [p["stiffness"] for p in points] == pytest.approx([ACROSS, 8 * ACROSS], rel=1e-6)


def test_it_is_a_form_of_the_workbench(server):
    from browser import CHROMIUM_FLAGS, chromium_path
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=chromium_path(), headless=True, args=CHROMIUM_FLAGS)
        page = chromium.new_page()
        page.goto(server.url + "/")
        page.wait_for_selector("body[data-ready=true]", state="attached", timeout=60_000)
        page.fill("#editor", json.dumps(CLAMPED_LINK))
        page.select_option("#analysis", "solve:body_stiffness")
        assert page.text_content("label[for=option-body]") == "Body"
        assert page.get_attribute("#option-body", "title") == "the body the force pushes"
        assert page.input_value("#option-direction") == "y"
        assert page.locator("#analysis option[value='job:stiffness_map']").count() == 1  # the job kind too
        page.fill("#option-body", "tip")
        page.click("#run")
        page.wait_for_function(
            "() => document.getElementById('run-state').textContent.includes('body_stiffness: converged')",
            timeout=60_000,
        )
        report = json.loads(page.text_content("#raw"))
        chromium.close()
    assert report["stiffness"] == pytest.approx(ACROSS, rel=1e-6)
