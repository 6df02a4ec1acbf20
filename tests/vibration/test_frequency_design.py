"""Frequencies' exact derivatives (the modes analysis' sensitivities) against central finite
differences of fresh modes runs, for a section height, a density or mass, and a load, about a
prestressed link and a loaded platform on a curved-beam flexure; repeated frequencies."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import EXAMPLES
from test_modes import EULER, pinned_pinned, platform_on_a_flexure

from flexmech.models import compile_mechanism, load_document
from flexmech.service.analyses import ANALYSES
from flexmech.service.analyses.base import AnalysisRequest


def modes_of(mech, **options) -> dict:
    return ANALYSES.named("modes").run(mech, AnalysisRequest(given=options))


def central_difference(mech, path: str, count: int) -> np.ndarray:
    value = mech.value(path)
    step = 1e-4 * abs(value)
    frequencies = []
    for sign in (1, -1):
        report = modes_of(mech.with_values({path: value + sign * step}), count=count)
        frequencies.append(np.array([m["frequency"] for m in report["modes"]]))
    return (frequencies[0] - frequencies[1]) / (2 * step)


def loaded_platform() -> dict:
    doc = platform_on_a_flexure()
    doc["loads"] = {"push": {"type": "force", "body": "platform", "force": [0.3, 2.0]}}
    return doc


@pytest.mark.parametrize(
    "document, fields",
    [
        (pinned_pinned(0.3 * EULER), ["/sections/strip/h", "/materials/steel/density", "/loads/pull/force/0"]),
        (loaded_platform(), ["/sections/blade/h", "/bodies/platform/mass", "/loads/push/force/1"]),
    ],
    ids=["prestressed link (elements' coordinates)", "loaded curved-beam platform (bodies' coordinates)"],
)
def test_frequency_derivatives_equal_central_differences(document, fields):
    mech = compile_mechanism(load_document(document))
    report = modes_of(mech, count=2, sensitivities=fields)
    for path in fields:
        exact = np.array([mode["sensitivities"][path] for mode in report["modes"]])
        assert exact == pytest.approx(central_difference(mech, path, 2), rel=1e-6), path
        assert report["units"]["sensitivities"][path].startswith("Hz/")


def test_repeated_frequencies_report_the_derivative_of_their_mean():
    """A mass on equal springs along x and y: one frequency twice. Stiffening x alone moves the
    x mode by 1 / (2 m omega) per unit of k (in rad/s) and the y mode not at all: each reports
    the mean, and the warning names both."""
    m, k = 0.5, 800.0
    doc = {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "bodies": {
            "ground": {"fixed": True, "position": [0, 0]},
            "puck": {"position": [0, 0], "mass": m, "inertia": 1e-3},
        },
        "elements": {
            "kx": {"type": "spring", "from": "ground", "to": "puck", "from_at": [-1, 0], "stiffness": k},
            "ky": {"type": "spring", "from": "ground", "to": "puck", "from_at": [0, -1], "stiffness": k},
            "turn": {"type": "spring", "kind": "torsional", "from": "ground", "to": "puck", "stiffness": 50.0},
        },
    }
    report = modes_of(compile_mechanism(load_document(doc)), count=2, sensitivities=["/elements/kx/stiffness"])
    omega = math.sqrt(k / m)
    assert [mode["omega"] for mode in report["modes"]] == pytest.approx([omega, omega], rel=1e-12)
    mean = 0.5 * (1 / (2 * m * omega)) / (2 * math.pi)
    assert [mode["sensitivities"]["/elements/kx/stiffness"] for mode in report["modes"]] == pytest.approx(
        [mean, mean], rel=1e-9
    )
    assert "modes 1, 2 share one frequency" in report["warnings"][-1]


def test_the_stage_example_maximizes_its_first_frequency_under_its_stroke_and_the_optimum_is_confirmed():
    """examples/stage_frequency.json: the blades' thickness h that maximizes the first frequency
    at rest while 5 N still moves the platform 1 mm. At rest the state is undeformed and the
    blades massless, so the frequency is exactly sqrt(24 E I / L^3 / m) / (2 pi) at the optimum's
    h (cubic elements are exact for the clamped-guided blade); the stroke constraint is active;
    its h is the linear theory's (F L^3 / (2 E b delta))^(1/3) but for the stroke's large-deflection
    stiffening (2e-4 measured)."""
    from flexmech.service.design.optimize import optimize
    from flexmech.service.design.problem import design_problem

    mech = compile_mechanism(load_document(EXAMPLES / "stage_frequency.json"))
    result = optimize(design_problem(mech, mech.document.optimize)).summary()
    assert result["status"] == "optimal" and result["ipopt_status"] == "Solve_Succeeded"
    h = result["design"]["/sections/blade/h"]
    E, b, L, m, F, stroke = 200e9, 0.01, 0.04, 0.2, 5.0, 1e-3
    rest = math.sqrt(24 * E * b * (h * 1e-3) ** 3 / 12 / L**3 / m) / (2 * math.pi)
    assert result["objective"] == pytest.approx(rest, rel=1e-6)
    assert h == pytest.approx((F * L**3 / (2 * E * b * stroke)) ** (1 / 3) * 1e3, rel=1e-3)
    stroke_row, stress_row = result["constraints"]
    assert stroke_row["active"] and stroke_row["value"] == pytest.approx(1.0, abs=1e-6)
    assert not stress_row["active"] and stress_row["value"] < 600
    moment = result["outputs"]["stroke"]["elements.left.M_start"]  # N mm: the bending stress is 6 |M| / (b h^2)
    assert stress_row["value"] == pytest.approx(6 * abs(moment) / (10 * h**2), rel=1e-12)
    fresh = modes_of(mech.with_values({"/sections/blade/h": h, "/loads/drive/force/0": 0.0}), count=1)
    assert fresh["modes"][0]["frequency"] == pytest.approx(result["objective"], rel=1e-6)


def test_a_frequency_response_bounds_a_design_at_the_closed_form():
    """The softest spring that keeps a 0.3 kg carriage's response to a 10 Hz force under 1 mm/N:
    undamped |H| = 1 / |k - m omega^2|, so k* = m omega^2 + 1000 N/m, the response's bound active."""
    from flexmech.service.design.optimize import optimize
    from flexmech.service.design.problem import design_problem

    m, limit, hertz = 0.3, 1e-3, 10.0
    doc = {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "bodies": {"ground": {"fixed": True, "position": [0, 0]}, "carriage": {"position": [1, 0], "mass": m}},
        "elements": {
            "rail": {"type": "slider", "from": "ground", "to": "carriage", "angle": 0},
            "coil": {"type": "spring", "from": "ground", "to": "carriage", "stiffness": 3000.0},
        },
        "loads": {"shake": {"type": "force", "body": "carriage", "force": [0.0, 0.0]}},
        "optimize": {
            "design": [{"path": "/elements/coil/stiffness", "lower": 1500, "upper": 5000}],
            "objective": {"output": "/elements/coil/stiffness", "sense": "minimize"},
            "constraints": [{"output": f"response(bodies.carriage.x, /loads/shake/force/0, {hertz})", "upper": limit}],
        },
    }
    mech = compile_mechanism(load_document(doc))
    result = optimize(design_problem(mech, mech.document.optimize)).summary()
    assert result["status"] == "optimal"
    expected = m * (2 * math.pi * hertz) ** 2 + 1 / limit
    assert result["design"]["/elements/coil/stiffness"] == pytest.approx(expected, rel=1e-7)
    (row,) = result["constraints"]
    assert row["active"] and row["value"] == pytest.approx(limit, rel=1e-7)
    response = ANALYSES.named("frequency_response").run(
        mech.with_values({"/elements/coil/stiffness": result["design"]["/elements/coil/stiffness"]}),
        AnalysisRequest(given={"input": "/loads/shake/force/0", "outputs": ["bodies.carriage.x"], "damping_ratio": 0,
                               "start": hertz * 0.999999, "stop": hertz, "points": 2}),
    )  # fmt: skip
    assert response["responses"]["bodies.carriage.x"]["amplitude"][-1] == pytest.approx(limit, rel=1e-6)


@pytest.mark.parametrize(
    "output, words",
    [
        ("response(bodies.cart.x, /loads/push/force/1, 10)", "no output 'bodies.cart.x'"),
        ("response(bodies.platform.x, /sections/blade/h, 10)", "name a load's force or moment component"),
        ("response(bodies.platform.x, /loads/push/force/1, fast)", "the frequency 'fast' is not a number"),
        ("frequency.0", "name a mode by its number from 1"),
    ],
)
def test_a_bad_vibration_output_in_a_design_is_named(output, words):
    from flexmech.models import MechanismError
    from flexmech.service.design.problem import design_problem

    doc = loaded_platform()
    doc["sections"]["blade"]["h"] = 0.0005
    doc["optimize"] = {
        "design": [{"path": "/sections/blade/h", "lower": 0.0002, "upper": 0.001}],
        "objective": {"output": output},
    }
    mech = compile_mechanism(load_document(doc))
    with pytest.raises(MechanismError) as err:
        design_problem(mech, mech.document.optimize)
    assert err.value.pointer == "/optimize/objective/output" and words in str(err.value)


def test_a_frequency_constraint_holds_the_thinnest_blades_at_the_closed_form():
    """The stage unloaded: the thinnest blades whose first frequency is at least 30 Hz, h^3 =
    m (2 pi 30)^2 L^3 / (2 E b); the frequency constraint is the active one, its value confirmed
    by a fresh modes run."""
    from flexmech.service.design.optimize import optimize
    from flexmech.service.design.problem import design_problem

    doc = json.loads((EXAMPLES / "stage_frequency.json").read_text())
    doc["loads"]["drive"]["force"] = [0, 0]
    doc["optimize"] = {
        "design": [{"path": "/sections/blade/h", "lower": 0.2, "upper": 1.5}],
        "objective": {"output": "/sections/blade/h", "sense": "minimize"},
        "constraints": [{"output": "frequency.1", "lower": 30.0}],
    }
    mech = compile_mechanism(load_document(doc))
    result = optimize(design_problem(mech, mech.document.optimize)).summary()
    assert result["status"] == "optimal"
    E, b, L, m = 200e9, 0.01, 0.04, 0.2
    h = (m * (2 * math.pi * 30) ** 2 * L**3 / (2 * E * b)) ** (1 / 3) * 1e3  # mm
    assert result["design"]["/sections/blade/h"] == pytest.approx(h, rel=1e-7)
    (row,) = result["constraints"]
    assert row["active"] and row["value"] == pytest.approx(30.0, rel=1e-7)
    fresh = modes_of(mech.with_values({"/sections/blade/h": result["design"]["/sections/blade/h"]}), count=1)
    assert fresh["modes"][0]["frequency"] == pytest.approx(30.0, rel=1e-7)
