"""The contact capability as a user meets it: bad `contacts` sections refused naming the
field and the problem (Python API and POST /v1/solve), states IPOPT cannot solve reported as
a status, the contact path job over real HTTP, friction along a motion, sensitivities
against finite differences, and `flexmech contact`.

Example I (examples/gripper_jaw_contact.json): the jaw rides on body `tip` (at (57, 0) mm,
undeformed), its triangle heel (0, 0), nose a = (19, 1.6), crest b = (0, 10.4598) in the
tip's axes; the circular fixture (R = 8.9 mm) is centred at (x_o, 10.5) mm.
"""

from __future__ import annotations

import json
import re
import time

import httpx
import numpy as np
import pytest
from conftest import EXAMPLES
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service import NewtonOptions
from flexmech.service.analyses.base import AnalysisRequest
from flexmech.service.analyses.contact import CONTACT

EXAMPLE = EXAMPLES / "gripper_jaw_contact.json"
X_O = "/contacts/objects/fixture/centre/0"
MU = "/contacts/pairs/insertion/friction"
H = "/sections/strip/h"
TIP = np.array([57.0, 0.0])  # the tip body's reference point, undeformed (tip angle 0)
JAW = np.array([[0.0, 0.0], [19.0, 1.6], [0.0, 10.4598]])  # in the tip's axes
FIXTURE_Y, RADIUS = 10.5, 8.9
ENV = {"COLUMNS": "200", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "NO_COLOR": "1"}


def example(x_o: float | None = None) -> dict:
    doc = json.loads(EXAMPLE.read_text())
    if x_o is not None:
        doc["contacts"]["objects"]["fixture"]["centre"][0] = x_o
    return doc


def compile_error(doc: dict) -> MechanismError:
    with pytest.raises(MechanismError) as info:
        compile_mechanism(load_document(doc))
    return info.value


def run_contact(doc: dict, options: NewtonOptions | None = None, **fields) -> dict:
    """The contact analysis through the Python API (what /v1/solve runs)."""
    return CONTACT.run(compile_mechanism(load_document(doc)), AnalysisRequest(options or NewtonOptions(), fields))


def analysis_error(doc: dict, **fields) -> MechanismError:
    with pytest.raises(MechanismError) as info:
        run_contact(doc, **fields)
    return info.value


def _error(response: httpx.Response) -> dict:
    """The one error shape of the API."""
    body = response.json()
    keys = set(body["error"]) - {"problems"}  # every field's problem, when several have one
    assert set(body) == {"error"} and keys == {"status", "code", "message", "pointer"}, body
    assert body["error"]["status"] == response.status_code
    return body["error"]


def post_solve(server, timeout: float = 60.0, **body) -> httpx.Response:
    return httpx.post(server.url + "/v1/solve", json={"analysis": "contact", **body}, timeout=timeout)


def solved(server, **body) -> dict:
    r = post_solve(server, **body)
    assert r.status_code == 200, r.text
    return r.json()


def assert_words(message: str, words: list[str]) -> None:
    for word in words:
        assert word in message, f"{word!r} not in {message!r}"


# --- A. bad input, each with its message ------------------------------------------------------
def _with_extras(doc: dict) -> dict:
    """A second object and site, so that lists of known names have more than one."""
    doc["contacts"]["objects"]["anvil"] = {"type": "half_plane", "point": [0, -30], "normal": [0, 1]}
    doc["contacts"]["sites"]["nose"] = {"type": "jaw", "body": "tip", "vertices": [[19, 1.6]]}
    return doc


def _unknown_site(doc):
    _with_extras(doc)["contacts"]["pairs"]["insertion"]["site"] = "jaww"


def _unknown_object(doc):
    _with_extras(doc)["contacts"]["pairs"]["insertion"]["object"] = "fixtur"


def _radius(value):
    def change(doc):
        doc["contacts"]["objects"]["fixture"]["radius"] = value

    return change


def _flat_ellipse(doc):
    doc["contacts"]["objects"]["fixture"] = {"type": "ellipse", "centre": [80, 10.5], "semi_axes": [0, 3]}


def _bow_tie_object(doc):
    doc["contacts"]["objects"]["fixture"] = {
        "type": "polygon",
        "vertices": [[0, 0], [4, 4], [4, 0], [0, 4]],
        "position": [80, 4],
    }


def _crossed_jaw(doc):
    doc["contacts"]["sites"]["jaw"]["vertices"] = [[0, 0], [19, 10], [19, 0], [0, 10]]


def _negative_friction(doc):
    doc["contacts"]["pairs"]["insertion"]["friction"] = -0.1


def _thin_surface(doc):
    doc["sections"]["strip"] = {"shape": "general", "I": 25.94, "A": 30.4}
    doc["contacts"]["sites"]["skin"] = {"type": "surface", "link": "finger", "side": "left"}
    doc["contacts"]["pairs"]["rub"] = {"site": "skin", "object": "fixture"}


def _implicit(expression):
    def change(doc):
        doc["contacts"]["objects"]["fixture"] = {"type": "implicit", "expression": expression, "position": [80, 10]}

    return change


def _misspelt(doc):
    doc["contacts"]["objects"]["fixture"]["raduis"] = doc["contacts"]["objects"]["fixture"].pop("radius")


UNSAFE = "unsafe or unsupported expression"
# (id, change to Example I, the pointer into the document, words of the message)
BAD_DOCUMENTS = [
    ("unknown-site", _unknown_site, "/contacts/pairs/insertion/site", ["unknown site 'jaww'", "jaw", "nose"]),
    (
        "unknown-object",
        _unknown_object,
        "/contacts/pairs/insertion/object",
        ["unknown object 'fixtur'", "fixture", "anvil"],
    ),
    ("zero-radius", _radius(0), "/contacts/objects/fixture/radius", ["must be positive", "got 0 mm"]),
    ("negative-radius", _radius(-1), "/contacts/objects/fixture/radius", ["must be positive", "got -1 mm"]),
    ("zero-semi-axis", _flat_ellipse, "/contacts/objects/fixture/semi_axes/0", ["must be positive", "got 0 mm"]),
    (
        "bow-tie-object",
        _bow_tie_object,
        "/contacts/objects/fixture/vertices",
        ["intersects itself", "edge 0-1 meets edge 2-3"],
    ),
    ("crossed-jaw", _crossed_jaw, "/contacts/sites/jaw/vertices", ["intersects itself", "edge 0-1 meets edge 2-3"]),
    ("negative-friction", _negative_friction, "/contacts/pairs/insertion/friction", ["must not be negative", "-0.1"]),
    (
        "surface-without-thickness",
        _thin_surface,
        "/contacts/sites/skin/side",
        ["link 'finger' has no thickness", "section 'strip'", "centre_line"],
    ),
    (
        "implicit-import",
        _implicit("__import__('os')"),
        "/contacts/objects/fixture/expression",
        [UNSAFE, "'__import__'", "not allowed"],
    ),
    ("implicit-attribute", _implicit("x.real"), "/contacts/objects/fixture/expression", [UNSAFE, "not allowed"]),
    ("implicit-open", _implicit("open"), "/contacts/objects/fixture/expression", [UNSAFE, "'open'", "not allowed"]),
    (
        "implicit-not-finite",
        _implicit("1/(x-x)"),
        "/contacts/objects/fixture/expression",
        ["not a finite number", "division by zero"],
    ),
    (
        "misspelt-radius",
        _misspelt,
        "/contacts/objects/fixture/raduis",
        ["unknown field 'raduis'", "did you mean 'radius'"],
    ),
]


@pytest.mark.parametrize(
    "change, pointer, words", [case[1:] for case in BAD_DOCUMENTS], ids=[case[0] for case in BAD_DOCUMENTS]
)
def test_bad_contacts_are_refused_by_the_python_api(change, pointer, words):
    doc = example()
    change(doc)
    error = compile_error(doc)
    assert error.pointer == pointer
    assert_words(error.problem, words)


@pytest.mark.parametrize(
    "change, pointer, words", [case[1:] for case in BAD_DOCUMENTS], ids=[case[0] for case in BAD_DOCUMENTS]
)
def test_bad_contacts_are_422_over_http_naming_the_field(api_server, change, pointer, words):
    doc = example()
    change(doc)
    r = post_solve(api_server, document=doc)
    error = _error(r)
    assert r.status_code == 422 and error["code"] == "invalid_input"
    assert error["pointer"] == "/document" + pointer
    assert_words(error["message"], words)


def penetration_depth(x_o: float) -> float:
    """How deep the fixture at x_o reaches into the undeformed jaw triangle (its centre
    outside it): R minus the distance from its centre to the nearest edge."""
    centre = np.array([x_o, FIXTURE_Y])
    vertices = TIP + JAW
    distances = []
    for a, b in zip(vertices, np.roll(vertices, -1, axis=0)):
        t = np.clip((centre - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
        distances.append(float(np.linalg.norm(centre - (a + t * (b - a)))))
    return RADIUS - min(distances)


def _reported_depth(message: str) -> float:
    found = re.search(r"by (-?[0-9.]+(?:e[-+]?[0-9]+)?) mm\b", message)
    assert found, f"no depth in mm in {message!r}"
    return float(found.group(1))


def test_penetration_depth_by_hand():
    """The geometry of the case below: at x_o = 70 the face ab is nearest (5.53 mm)."""
    assert penetration_depth(70.0) == pytest.approx(8.9 - 5.5305, abs=1e-3)
    assert penetration_depth(80.0) < 0  # the example's own start is clear


def test_a_penetrating_start_is_refused_or_approached_python():
    doc = example(70.0)
    error = analysis_error(doc, penetrating_start="refuse")
    assert error.pointer == "/document/contacts/pairs/insertion"
    assert_words(error.problem, ["object 'fixture'", "site 'jaw'", "penetrates", "mm"])
    assert f"{_reported_depth(error.problem):.3g}" == f"{penetration_depth(70.0):.3g}", error.problem
    report = run_contact(doc)  # approach, the default
    assert report["status"] == "converged" and report["approach_steps"] >= 2
    assert report["pairs"]["insertion"]["state"] != "open"


def test_a_penetrating_start_is_refused_or_approached_http(api_server):
    r = post_solve(api_server, example="gripper_jaw_contact", overrides={X_O: 70}, penetrating_start="refuse")
    error = _error(r)
    assert r.status_code == 422 and error["pointer"] == "/document/contacts/pairs/insertion"
    assert_words(error["message"], ["object 'fixture'", "site 'jaw'", "penetrates", "mm"])
    assert f"{_reported_depth(error['message']):.3g}" == f"{penetration_depth(70.0):.3g}", error["message"]
    answer = solved(api_server, example="gripper_jaw_contact", overrides={X_O: 70})
    assert answer["status"] == "converged" and answer["approach_steps"] >= 2


def _shooting_surface() -> dict:
    doc = example()
    finger = doc["elements"]["finger"]
    finger["discretization"] = "shooting"
    finger.pop("degree")
    doc["contacts"]["sites"]["skin"] = {"type": "surface", "link": "finger", "side": "left"}
    doc["contacts"]["pairs"]["rub"] = {"site": "skin", "object": "fixture"}
    return doc


SHOOTING_WORDS = re.compile(r"discretization\W+(?:to\W+)?elements")


def test_a_surface_on_a_shooting_link_is_refused_naming_the_element_and_the_change(api_server):
    """The contact analysis needs the link's energy: refused naming the element and what to
    change (discretization "elements"), not a crash."""
    doc = _shooting_surface()
    error = analysis_error(doc)
    assert error.pointer == "/document/elements/finger"
    assert "'finger'" in error.problem
    assert SHOOTING_WORDS.search(error.problem), f"the message does not say what to change: {error.problem!r}"
    r = post_solve(api_server, document=doc)
    body = _error(r)
    assert r.status_code == 422 and body["pointer"] == "/document/elements/finger"
    assert SHOOTING_WORDS.search(body["message"]), body["message"]


def test_contacts_without_pairs_cannot_be_a_contact_analysis(api_server):
    doc = example()
    doc["contacts"]["pairs"] = {}
    compile_mechanism(load_document(doc))  # a document may hold objects and sites only
    error = analysis_error(doc)
    assert error.pointer == "/document/contacts/pairs"
    assert "needs at least one contact pair" in error.problem
    r = post_solve(api_server, document=doc)
    body = _error(r)
    assert r.status_code == 422 and body["pointer"] == "/document/contacts/pairs"
    assert "needs at least one contact pair" in body["message"]


# --- B. what IPOPT cannot solve is a status ---------------------------------------------------
def _squeezed() -> dict:
    """The tip point between two half-planes with no room: free space y >= 1 and y <= -1."""
    doc = example()
    doc["contacts"] = {
        "objects": {
            "above": {"type": "half_plane", "point": [0, 1], "normal": [0, 1]},
            "below": {"type": "half_plane", "point": [0, -1], "normal": [0, -1]},
        },
        "sites": {"point": {"type": "jaw", "body": "tip", "vertices": [[0, 0]]}},
        "pairs": {"up": {"site": "point", "object": "above"}, "down": {"site": "point", "object": "below"}},
    }
    return doc


def test_a_time_limit_stops_the_state_with_a_status_python():
    report = run_contact(example(67.81), NewtonOptions(time_limit=1e-6))
    assert report["status"] == "time_limit"
    assert "time limit" in report["message"], report["message"]


def test_a_time_limit_stops_the_state_with_a_status_http(api_server):
    answer = solved(api_server, example="gripper_jaw_contact", overrides={X_O: 67.81}, options={"time_limit": 1e-6})
    assert answer["status"] == "time_limit"
    assert "time limit" in answer["message"], answer["message"]


def test_an_impossible_configuration_is_a_status_python():
    report = run_contact(_squeezed())
    assert report["status"] != "converged"
    assert report["message"] and "infeasib" in report["message"].lower(), report["message"]


def test_an_impossible_configuration_is_a_status_http(api_server):
    r = post_solve(api_server, document=_squeezed())
    assert r.status_code == 200, r.text
    answer = r.json()
    assert answer["status"] != "converged"
    assert answer["message"] and "infeasib" in answer["message"].lower(), answer["message"]


# --- C. the contact path job -----------------------------------------------------------------
def _wait_for_job(server, job_id: str, timeout: float = 60.0) -> dict:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        status = httpx.get(f"{server.url}/v1/jobs/{job_id}").json()
        if status["status"] in ("succeeded", "failed", "cancelled"):
            return status
        time.sleep(0.05)
    raise AssertionError(f"job {job_id} did not finish in {timeout} s")


def test_contact_path_job_over_http_equals_single_states(api_server):
    path = [{"path": X_O, "start": 78, "stop": 60, "steps": 18}]
    r = httpx.post(api_server.url + "/v1/contacts", json={"example": "gripper_jaw_contact", "path": path})
    assert r.status_code == 202, r.text
    job = r.json()
    assert job["kind"] == "contact" and job["progress"]["total"] == 19
    final = _wait_for_job(api_server, job["id"])
    assert final["status"] == "succeeded", final["error"]
    body = httpx.get(f"{api_server.url}/v1/jobs/{job['id']}/result").json()
    assert body["complete"]
    result = body["result"]
    np.testing.assert_allclose(result["parameters"][0]["values"], np.linspace(78, 60, 19), rtol=0, atol=1e-12)
    assert result["parameters"][0]["unit"] == "mm" and result["force_unit"] == "N"
    points = result["points"]
    assert [p["index"] for p in points] == list(range(19))
    for k, p in enumerate(points):
        assert p["values"] == [pytest.approx(78 - k, abs=1e-12)]
        assert p["status"] == "converged", p["message"]
        assert set(p["pairs"]) == {"insertion"} and "contacts.insertion.force_x" in p["outputs"]
        assert p["outputs"]["contacts.insertion.force_x"] == pytest.approx(
            p["pairs"]["insertion"]["force"][0], rel=1e-12, abs=1e-12
        )
    at_64 = points[14]
    assert at_64["values"] == [pytest.approx(64.0)] and at_64["pairs"]["insertion"]["state"] == "frictionless"
    single = solved(api_server, example="gripper_jaw_contact", overrides={X_O: 64})
    assert single["status"] == "converged"
    expected = single["pairs"]["insertion"]["force"][0]
    assert expected < 0
    assert at_64["outputs"]["contacts.insertion.force_x"] == pytest.approx(expected, rel=1e-9)


def test_contact_path_job_with_a_bad_pointer_is_422(api_server):
    path = [{"path": "/contacts/objects/fixtur/centre/0", "start": 78, "stop": 60, "steps": 18}]
    r = httpx.post(api_server.url + "/v1/contacts", json={"example": "gripper_jaw_contact", "path": path})
    error = _error(r)
    assert r.status_code == 422 and error["pointer"] == "/path/0/path"
    assert "not a numeric field" in error["message"]


# --- D. friction along a motion ----------------------------------------------------------------
def test_friction_slips_along_the_given_motion(api_server):
    answer = solved(api_server, example="gripper_jaw_contact", overrides={X_O: 67.81, MU: 0.5}, motion={X_O: -1})
    assert answer["status"] == "converged"
    pair = answer["pairs"]["insertion"]
    assert pair["state"] == "slipping"
    assert pair["normal_force"] > 0
    assert abs(abs(pair["friction_force"]) - 0.5 * pair["normal_force"]) <= 1e-9 * pair["normal_force"]
    assert not any("direction of sliding" in w for w in answer["warnings"]), answer["warnings"]
    without = solved(api_server, example="gripper_jaw_contact", overrides={X_O: 67.81, MU: 0.5})
    assert without["status"] == "converged"
    assert any("friction needs the direction of sliding" in w for w in without["warnings"]), without["warnings"]
    assert without["pairs"]["insertion"]["friction_force"] == 0.0


# --- E. sensitivities against finite differences -------------------------------------------------
OUTPUTS = ["contacts.insertion.force_x", "contacts.insertion.normal_force", "elements.finger.y_end"]
STEPS = {X_O: 1e-4, H: 1e-5}  # mm


def _values(answer: dict) -> dict[str, float]:
    assert answer["status"] == "converged", answer["message"]
    pair = answer["pairs"]["insertion"]
    return {
        "contacts.insertion.force_x": pair["force"][0],
        "contacts.insertion.normal_force": pair["normal_force"],
        "elements.finger.y_end": answer["outputs"]["elements.finger.y_end"],
    }


@pytest.mark.parametrize("mu, motion", [(0.0, None), (0.5, {X_O: -1})], ids=["frictionless", "slipping"])
def test_sensitivities_equal_central_differences(api_server, mu, motion):
    """Slipping, the friction coefficient too: it acts through the slipping rows' phi = mu
    sigma, whose derivative the KKT system's p-Jacobian alone missed (0 reported, tens of
    newtons per unit mu by differences)."""
    base = {X_O: 67.81, MU: mu, H: 3.2}
    extra = {"motion": motion} if motion else {}
    steps = {**STEPS, MU: 1e-5} if motion else STEPS
    answer = solved(
        api_server,
        example="gripper_jaw_contact",
        overrides=base,
        **extra,
        sensitivities={"parameters": list(steps), "outputs": OUTPUTS},
    )
    assert answer["status"] == "converged"
    if motion:
        assert answer["pairs"]["insertion"]["state"] == "slipping"
    found = answer["sensitivities"]["derivatives"]
    assert answer["sensitivities"]["units"]["contacts.insertion.force_x"][X_O] == "N/mm"
    differences = {}
    for parameter, step in steps.items():
        up = _values(
            solved(
                api_server,
                example="gripper_jaw_contact",
                overrides={**base, parameter: base[parameter] + step},
                **extra,
            )
        )
        down = _values(
            solved(
                api_server,
                example="gripper_jaw_contact",
                overrides={**base, parameter: base[parameter] - step},
                **extra,
            )
        )
        differences[parameter] = {name: (up[name] - down[name]) / (2 * step) for name in OUTPUTS}
    for name in OUTPUTS:
        # relative to the output's largest derivative: y_end does not depend on h (a single
        # frictionless tip force: the shape depends on F/EI only), so its own size is ~0
        scale = max(abs(differences[p][name]) for p in steps)
        for parameter in steps:
            exact, fd = found[name][parameter], differences[parameter][name]
            assert abs(exact - fd) <= 1e-5 * max(abs(fd), scale), (name, parameter, exact, fd)


SLIDING_OUTPUTS = OUTPUTS[:2]


def _slipping(x_o: float, mu: float, **fields) -> dict:
    doc = example(x_o)
    doc["contacts"]["pairs"]["insertion"]["friction"] = mu
    answer = run_contact(doc, motion={X_O: -1}, **fields)
    assert answer["status"] == "converged" and answer["pairs"]["insertion"]["state"] == "slipping", answer["message"]
    return answer


@pytest.mark.parametrize("x_o", [60.0, 64.0, 66.0, 67.81, 70.0, 72.0])
def test_friction_sensitivities_of_a_slipping_jaw_equal_central_differences(x_o):
    """Example I, mu = 0.5, the fixture withdrawing: d/d mu of the pair's force_x and normal
    force, exact, against central differences in mu (1e-5 relative; they agree to ~1e-10)."""
    found = _slipping(x_o, 0.5, sensitivities={"parameters": [MU], "outputs": SLIDING_OUTPUTS})
    step = 1e-5
    up, down = (_values(_slipping(x_o, 0.5 + sign * step)) for sign in (1, -1))
    for name in SLIDING_OUTPUTS:
        exact, fd = found["sensitivities"]["derivatives"][name][MU], (up[name] - down[name]) / (2 * step)
        assert abs(fd) > 1.0 and abs(exact - fd) <= 1e-5 * abs(fd), (name, exact, fd)


def _onset() -> tuple[float, float]:
    """Fixture positions (mm) 1e-12 apart about where the jaw first touches: (touching, open)."""
    touching, apart = 70.0, 80.0
    while apart - touching > 1e-12:
        middle = 0.5 * (touching + apart)
        if run_contact(example(middle))["pairs"]["insertion"]["state"] == "open":
            apart = middle
        else:
            touching = middle
    return touching, apart


def test_no_derivative_is_given_where_the_contact_is_about_to_change_state():
    """At the onset, from either side, the outputs have one-sided derivatives only: none is
    given, and the answer names the pair and why; clear of it, an open pair's forces have
    derivative 0 (not norm_2's 0/0) and a touching one numbers."""
    asked = {"parameters": [X_O], "outputs": OUTPUTS}
    for x_o, why in zip(
        _onset(), ("touches with a vanishing force (about to open)", "is apart by a vanishing gap (about to touch)")
    ):
        found = run_contact(example(x_o), sensitivities=asked)["sensitivities"]
        assert all(row[X_O] is None for row in found["derivatives"].values()), found
        assert found["not_differentiable"] == [f"pair 'insertion' {why}: the derivatives are one-sided, none is given"]
    clear = run_contact(example(78.5), sensitivities=asked)["sensitivities"]
    assert all(row[X_O] == 0.0 for row in clear["derivatives"].values()) and "not_differentiable" not in clear
    touching = run_contact(example(77.9), sensitivities=asked)["sensitivities"]
    assert all(row[X_O] is not None and row[X_O] != 0.0 for row in touching["derivatives"].values()), touching


# --- F. the command line -----------------------------------------------------------------------
@pytest.fixture
def run():
    runner = CliRunner()
    return lambda *args: runner.invoke(app, [str(a) for a in args], env=ENV)


def test_cli_path_writes_json_and_figures(run, tmp_path):
    out, plot, shapes = tmp_path / "out.json", tmp_path / "f.png", tmp_path / "s.png"
    result = run("contact", EXAMPLE, "--json", out, "--plot", plot, "--shapes", shapes)
    assert result.exit_code == 0, result.output
    data = json.loads(out.read_text())
    points = data["points"]
    assert len(points) == 101
    assert all(p["status"] == "converged" for p in points)
    np.testing.assert_allclose([p["values"][0] for p in points], np.linspace(80, 45, 101), atol=1e-12)
    assert any(p["pairs"]["insertion"]["state"] == "frictionless" for p in points)
    for figure in (plot, shapes):
        assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and figure.stat().st_size > 1000
    assert "101 of 101 states converged" in result.stdout


def test_cli_single_state_prints_the_pair(run):
    result = run("contact", EXAMPLE, "--single", "--set", f"{X_O}=67.81")
    assert result.exit_code == 0, result.output
    report = run_contact(example(67.81))
    pair = report["pairs"]["insertion"]
    rows = [line for line in result.stdout.splitlines() if "insertion" in line]
    assert len(rows) == 1, result.stdout
    assert pair["state"] == "frictionless" and "frictionless" in rows[0]
    assert f" {pair['normal_force']:.6g} " in rows[0] and f" {pair['force'][0]:.6g} " in rows[0], rows[0]
    assert "normal [N]" in result.stdout and "F_x [N]" in result.stdout  # the unit in the column's head
    assert "converged" in result.stdout


def test_cli_bad_at_is_a_one_line_error(run, tmp_path):
    result = run("contact", EXAMPLE, "--at", "999", "--shapes", tmp_path / "s.png")
    assert result.exit_code == 2, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: --at") and "999" in lines[0], lines[0]
    assert not (tmp_path / "s.png").exists()


def test_the_python_client_runs_a_contact_path_and_reads_it_typed(api_server):
    """api.client: contact_path, wait, result parsed as a ContactPathResult (pairs typed)."""
    from flexmech.api.client import Client
    from flexmech.api.job_schemas import ContactPathResult

    with Client(api_server.url) as client:
        job = client.contact_path(
            example="gripper_jaw_contact", path=[{"path": X_O, "start": 70, "stop": 66, "steps": 4}]
        )
        assert client.wait(job.id, timeout=120).status == "succeeded"
        result = client.result(job.id).result
    assert isinstance(result, ContactPathResult) and len(result.points) == 5
    forces = [p.pairs["insertion"].force[0] for p in result.points]
    assert all(p.pairs["insertion"].state == "frictionless" for p in result.points)
    assert np.all(np.diff(forces) < 0)  # the fixture moving in pushes the finger harder


def test_a_contact_problem_too_large_to_build_is_refused_before_building(api_server):
    """256 pairs of a 64-vertex jaw against a 64-vertex polygon would build millions of rows:
    422 naming the pair where the estimate passes the limit, answered at once."""
    doc = example()
    square = [[0, 0], [1, 0], [1, 1], [0, 1]]
    doc["contacts"]["objects"]["block"] = {"type": "polygon", "vertices": square * 16, "position": [200, 200]}
    doc["contacts"]["sites"]["saw"] = {
        "type": "jaw",
        "body": "tip",
        "closed": False,
        "vertices": [[k, (k % 2) * 0.5] for k in range(64)],
    }
    doc["contacts"]["pairs"] = {f"p{k}": {"site": "saw", "object": "block"} for k in range(3)}
    r = httpx.post(api_server.url + "/v1/solve", json={"document": doc, "analysis": "contact"})
    error = _error(r)
    assert r.status_code == 422 and error["pointer"] == "/document/contacts/pairs/p0"
    assert "non-penetration rows: the limit is 2000" in error["message"]


def test_too_many_link_rotations_for_a_contact_problem_are_refused_at_once(api_server):
    doc = example()
    doc["elements"]["finger"].update(intervals=64, degree=3)
    r = httpx.post(api_server.url + "/v1/solve", json={"document": doc, "analysis": "contact"})
    error = _error(r)
    assert r.status_code == 422 and error["pointer"] == "/document/elements/finger/intervals"
    assert "at most 128 rotations" in error["message"]


def test_cli_compares_frictionless_and_frictional_runs(run, tmp_path):
    """--friction 0 --friction 0.5: two runs of the path, both in the JSON and on the plot;
    friction makes the insertion harder at every touching state of the face."""
    out, plot = tmp_path / "runs.json", tmp_path / "runs.svg"
    result = run(
        "contact",
        EXAMPLE,
        "--path",
        X_O,
        "--start",
        78,
        "--stop",
        64,
        "--steps",
        14,
        "--friction",
        0,
        "--friction",
        0.5,
        "--json",
        out,
        "--plot",
        plot,
    )
    assert result.exit_code == 0, result.output
    assert "mu = 0:" in result.output and "mu = 0.5:" in result.output
    runs = json.loads(out.read_text())["runs"]
    assert [r["friction"] for r in runs] == [0.0, 0.5]
    plain, rubbing = ([p["pairs"]["insertion"] for p in r["points"]] for r in runs)
    touching = [(a, b) for a, b in zip(plain, rubbing) if a["state"] != "open"]
    assert len(touching) > 10 and all(b["force"][0] < a["force"][0] < 0 for a, b in touching)
    assert all(b["state"] == "slipping" for _, b in touching)
    assert plot.read_text().count("<path") > 10 and "mu = 0.5" in plot.read_text()
