"""The drawing the workbench shows (service.drawings.drawing over POST /v1/drawings), the document
text reader (POST /v1/documents/parse), and the page's files as the service serves them."""

from __future__ import annotations

import json
import math
import re

import httpx
import numpy as np
import pytest
from conftest import EXAMPLES

from flexmech.models import compile_mechanism, load_document
from flexmech.service import solve_equilibrium
from flexmech.service.drawings.drawing import mechanism_drawing

WEB = EXAMPLES.parent / "api" / "web"


def placed(drawing: dict, pose: list[float], body: str, point) -> np.ndarray:
    """The page's transformation (scene.js placed()): a body's point moved by its pose."""
    about = np.asarray(drawing["bodies"][body]["reference"])
    c, s = math.cos(pose[2]), math.sin(pose[2])
    u = np.asarray(point) - about
    return about + np.asarray(pose[:2]) + np.array([c * u[0] - s * u[1], s * u[0] + c * u[1]])


def test_the_gripper_flexures_are_drawn_on_their_arcs_and_their_ends_move_with_their_bodies(gripper_dict):
    mech = compile_mechanism(load_document(gripper_dict))
    result = solve_equilibrium(mech)
    drawing = mechanism_drawing(result.mechanism, result.z, result.outputs())
    for element in drawing["elements"]:
        spec = gripper_dict["elements"][element["name"]]
        points = np.asarray(element["points"])
        radii = np.hypot(*(points - spec["center"]).T)
        assert radii == pytest.approx(spec["radius"], rel=1e-9)  # the undeformed arc
        a, b = (math.radians(spec["start_angle"] + t) for t in (0.0, spec["arc_angle"]))
        ends = {tuple(np.round(p, 9)) for p in points[[0, -1]]}
        arc_ends = {
            tuple(np.round(np.add(spec["center"], spec["radius"] * np.array([math.cos(t), math.sin(t)])), 9))
            for t in (a, b)
        }
        assert ends == arc_ends
        deformed = np.asarray(drawing["deformed"]["elements"][element["name"]])
        poses = drawing["deformed"]["poses"]
        for body, undeformed_end, deformed_end in (
            (element["from"], points[0], deformed[0]),
            (element["to"], points[-1], deformed[-1]),
        ):
            # a flexure is clamped to its bodies: its ends move rigidly with them
            assert placed(drawing, poses[body], body, undeformed_end) == pytest.approx(deformed_end, abs=1e-9)
    outputs = result.outputs()
    assert drawing["deformed"]["poses"]["input"][1] == pytest.approx(outputs["bodies.input.y"] - 0.2, abs=1e-12)
    assert drawing["units"]["length"] == "mm" and drawing["loads"][0]["vector"] == [0.0, 50.0]


def test_objects_and_impact_surfaces_are_drawn_at_their_size():
    jaw = mechanism_drawing(compile_mechanism(load_document(EXAMPLES / "gripper_jaw_contact.json")))
    (fixture,) = jaw["outlines"]
    assert np.hypot(*(np.asarray(fixture["points"]) - [80, 10.5]).T) == pytest.approx(8.9, rel=1e-12)
    csfh = mechanism_drawing(compile_mechanism(load_document(EXAMPLES / "csfh.json")))
    radii = {o["name"]: np.hypot(*np.asarray(o["points"]).T) for o in csfh["outlines"]}
    assert radii["pin"] == pytest.approx(0.18) and radii["hole"] == pytest.approx(0.20)
    assert {o["name"]: o["solid"] for o in csfh["outlines"]} == {"pin": True, "hole": False}


def test_drawings_and_document_text_over_http(api_server, gripper_dict):
    url = api_server.url
    answer = httpx.post(f"{url}/v1/drawings", json={"example": "gripper", "state": "equilibrium"}, timeout=60).json()
    assert answer["status"] == "converged" and set(answer["deformed"]["poses"]) == {
        "frame",
        "input",
        "coupler",
        "follower",
    }
    broken = json.loads(json.dumps(gripper_dict))
    broken["elements"]["c"]["to"] = "folower"
    error = httpx.post(f"{url}/v1/drawings", json={"document": broken}, timeout=60).json()["error"]
    assert error["pointer"] == "/document/elements/c/to" and "unknown body 'folower'" in error["message"]
    yaml_text = "name: two bodies\nbodies:\n  ground: {fixed: true, position: [0, 0]}\n"
    parsed = httpx.post(f"{url}/v1/documents/parse", json={"text": yaml_text}, timeout=30).json()
    assert parsed == {
        "document": {"name": "two bodies", "bodies": {"ground": {"fixed": True, "position": [0, 0]}}},
        "format": "yaml",
    }
    error = httpx.post(f"{url}/v1/documents/parse", json={"text": "bodies: [1, 2\n"}, timeout=30).json()["error"]
    assert error["status"] == 422 and error["pointer"] == "/text" and "not valid YAML" in error["message"]
    assert "line 2" in error["message"]
    laughs = "a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1]\n" + "".join(
        f"{b}: &{b} [{', '.join(['*' + a] * 9)}]\n" for a, b in zip("abcdefgh", "bcdefghi")
    )  # 9^9 ones
    error = httpx.post(f"{url}/v1/documents/parse", json={"text": laughs}, timeout=30).json()["error"]
    assert error["pointer"] == "/text" and "aliases (*name) are not accepted here" in error["message"]


def test_the_page_and_its_modules_are_served_from_the_package(api_server):
    url = api_server.url
    for path in ("/", "/jobs/0123456789abcdef0123456789abcdef"):
        page = httpx.get(url + path, timeout=30)
        assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
        assert "default-src 'self'" in page.headers["content-security-policy"]
        assert '<script type="module" src="/workbench/main.js">' in page.text
    modules = sorted(WEB.glob("*.js"))
    for module in modules:
        served = httpx.get(f"{url}/workbench/{module.name}", timeout=30)
        assert served.status_code == 200 and served.text == module.read_text()
        for imported in re.findall(r'from "\./([a-z_]+\.js)"', module.read_text()):
            assert (WEB / imported).exists(), f"{module.name} imports {imported}, which is not in the package"
        assert not re.search(r"https?://(?!www\.w3\.org/)", module.read_text()), f"{module.name} names another host"


def test_a_load_path_is_drawn_state_by_state(api_server, gripper_dict):
    body = {"example": "gripper", "state": "path", "path": {"path": "/loads/actuation/force/1", "values": [0, 40, 80]}}
    answer = httpx.post(f"{api_server.url}/v1/drawings", json=body, timeout=60).json()
    assert [f["value"] for f in answer["frames"]] == [0, 40, 80] and answer["unit"] == "uN"
    assert all(f["status"] == "converged" for f in answer["frames"])
    assert answer["frames"][0]["poses"]["input"] == pytest.approx([0, 0, 0], abs=1e-12)  # no load: undeformed
    mech = compile_mechanism(load_document(gripper_dict)).with_values({"/loads/actuation/force/1": 80})
    alone = mechanism_drawing(mech, (result := solve_equilibrium(mech)).z, result.outputs())["deformed"]
    for body_name, pose in alone["poses"].items():
        assert answer["frames"][2]["poses"][body_name] == pytest.approx(pose, abs=1e-9)
    hurried = {
        **body,
        "options": {"time_limit": 1e-6},
        "path": {"path": "/loads/actuation/force/1", "values": list(range(300))},
    }
    answer = httpx.post(f"{api_server.url}/v1/drawings", json=hurried, timeout=60).json()
    assert answer["status"] == "time_limit" and 1 <= len(answer["frames"]) < 300
    assert answer["message"] == f"{len(answer['frames'])} of 300 states drawn in the time limit"
    too_many = {**body, "path": {"path": "/loads/actuation/force/1", "values": list(range(401))}}
    error = httpx.post(f"{api_server.url}/v1/drawings", json=too_many, timeout=60).json()["error"]
    assert error["status"] == 422 and error["pointer"] == "/path/values"
    error = httpx.post(f"{api_server.url}/v1/drawings", json={"example": "gripper", "state": "path"}, timeout=60).json()
    assert "give path with state 'path'" in error["error"]["message"]


def test_the_client_draws_and_reads_a_jobs_request(api_server):
    from pydantic import ValidationError

    from flexmech.api.client import Client

    with Client(api_server.url) as flexmech:
        drawing = flexmech.drawing(example="gripper_jaw_contact")
        assert drawing["status"] == "undeformed" and drawing["outlines"][0]["name"] == "fixture"
        job = flexmech.sweep(example="gripper", parameters=[{"path": "/loads/actuation/force/1", "values": [10, 20]}])
        asked = flexmech.job_request(job.id)
        assert asked["kind"] == "sweep" and asked["document"]["name"].startswith("MEMS gripper")
        assert asked["parameters"] == [{"path": "/loads/actuation/force/1", "values": [10.0, 20.0]}]
        with pytest.raises(ValidationError) as refused:
            flexmech.drawing(example="gripper", state="path")  # refused before it is sent
        assert "give path with state 'path'" in str(refused.value)


def test_each_connector_is_drawn_by_the_glyph_and_points_its_family_gives():
    """Pins, sliders and springs come to the page with their family's glyph (models.elements:
    connector()), their points where the document puts them (the body's reference point where
    it leaves them out), a slider's axis in rad and a spring's kind."""
    doc = {
        "units": {"length": "mm", "force": "N", "angle": "deg"},
        "bodies": {
            "ground": {"fixed": True, "position": [0, 0]},
            "carriage": {"position": [10, 2]},
            "arm": {"position": [20, 2]},
        },
        "elements": {
            "rail": {"type": "slider", "from": "ground", "to": "carriage", "angle": 30},
            "hinge": {"type": "pin", "from": "carriage", "to": "arm", "at": [15, 2]},
            "coil": {
                "type": "spring",
                "from": "ground",
                "to": "arm",
                "stiffness": 1.0,
                "from_at": [0, 5],
                "to_at": [20, 5],
            },
            "twist": {"type": "spring", "kind": "torsional", "from": "carriage", "to": "arm", "stiffness": 1.0},
        },
    }
    drawn = {c["name"]: c for c in mechanism_drawing(compile_mechanism(load_document(doc)))["connectors"]}
    assert {name: c["glyph"] for name, c in drawn.items()} == {
        "rail": "slider",
        "hinge": "pin",
        "coil": "zigzag",
        "twist": "zigzag",
    }
    assert drawn["rail"]["points"] == [[10, 2]] and drawn["rail"]["angle"] == pytest.approx(math.pi / 6)
    assert drawn["hinge"]["points"] == [[15, 2]] and drawn["hinge"]["bodies"] == ["carriage", "arm"]
    assert drawn["coil"]["points"] == [[0, 5], [20, 5]] and drawn["coil"]["kind"] == "translational"
    assert drawn["twist"]["points"] == [[10, 2], [20, 2]] and drawn["twist"]["kind"] == "torsional"
    scene = (WEB / "scene.js").read_text()
    assert 'joint.glyph === "zigzag"' in scene and 'joint.glyph === "slider"' in scene  # the page draws by glyph
