"""A circle against polygon and ellipse objects in impact simulations (models.impacts.pairs):
seed 004's pin (radius 0.18 m, 10 kg) falls from rest under gravity onto a fixed block (on its
flat top, past its corner) or an ellipse (on its top, off its axis), and meets it when free
fall brings it there; the ellipse's state derivatives equal central differences."""

from __future__ import annotations

import math

import numpy as np
import pytest
from impact_cases import as_moreau, csfh
from scipy.optimize import brentq, minimize_scalar

from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service.analysis import run_analysis
from flexmech.service.impacts.study import variant
from flexmech.service.solvers.newton import NewtonOptions

G, RADIUS, TOP, CORNER = 9.81, 0.18, -0.3, 1.0  # the block's top at y = -0.3 m, its right edge at x = 1 m


def simulated(doc: dict) -> dict:
    """The simulate analysis of the document, as the service and the CLI run it."""
    return run_analysis(compile_mechanism(load_document(doc)), "simulate", NewtonOptions())


def falling_on_a_block(scheme: str, start_x: float) -> dict:
    doc = csfh("6.1", scheme=scheme, until=0.25, step=1e-5 if scheme == "moreau" else 1e-4)
    doc["contacts"]["objects"] = {
        "block": {"type": "polygon", "vertices": [[-1, -1], [0, -1], [0, 0], [-1, 0]], "position": [CORNER, TOP]}
    }
    doc["contacts"]["pairs"]["conjugate"]["object"] = "block"
    doc["simulate"]["initial"]["hinge"] = {"displacement": [start_x, 0, 0]}
    return doc


@pytest.mark.parametrize("scheme", ["event_driven", "moreau"])
def test_a_pin_falling_on_the_flat_top_meets_it_after_free_fall(scheme):
    report = simulated(falling_on_a_block(scheme, 0.0))
    drop = -TOP - RADIUS
    first = report["impacts"][0]
    if scheme == "event_driven":
        assert first["time"] == pytest.approx(math.sqrt(2 * drop / G), rel=1e-8)
        assert first["impact_speed"] == pytest.approx(math.sqrt(2 * G * drop), rel=1e-8)
    else:
        assert abs(first["time"] - math.sqrt(2 * drop / G)) <= 1e-5
    x = np.array(report["coordinates"]["hinge.x"])
    assert np.abs(x).max() < 1e-6  # pushed straight up by the top edge


def test_a_pin_falling_past_the_corner_meets_the_vertex_and_is_pushed_away_from_it():
    """Its centre 0.1 m beyond the corner: it meets the vertex when (y - top)^2 + 0.1^2 = R^2,
    and the vertex pushes it along the line from the vertex to its centre (down and right)."""
    offset = 0.1
    report = simulated(falling_on_a_block("event_driven", CORNER + offset))
    drop = -TOP - math.sqrt(RADIUS**2 - offset**2)
    first = report["impacts"][0]
    assert first["time"] == pytest.approx(math.sqrt(2 * drop / G), rel=1e-8)
    times, vx = np.array(report["times"]), np.array(report["velocities"]["hinge.x"])
    after = times > first["time"] + first["duration"]
    assert vx[after][0] > 0.1 * first["impact_speed"]  # the vertex threw it sideways
    assert np.abs(vx[times < first["time"]]).max() < 1e-9


SEMI_AXES, TILT = (0.4, 0.1), 20.0  # m; deg: the ellipse's axis from the x axis
ELLIPSE_CENTRE = (0.0, -0.45)


def falling_on_an_ellipse(start_x: float, tilt: float = 0.0, until: float = 0.25) -> dict:
    doc = csfh("6.1", until=until)
    doc["contacts"]["objects"] = {
        "egg": {"type": "ellipse", "centre": list(ELLIPSE_CENTRE), "semi_axes": list(SEMI_AXES), "angle": tilt}
    }
    doc["contacts"]["pairs"]["conjugate"]["object"] = "egg"
    doc["simulate"]["initial"]["hinge"] = {"displacement": [start_x, 0, 0]}
    return doc


def distance_to_ellipse(point, tilt: float) -> float:
    """By a bounded scalar search over the boundary's parameter, finely bracketed (independent
    of the simulation's foot point)."""
    turn = math.radians(tilt)
    local = np.array([[math.cos(turn), math.sin(turn)], [-math.sin(turn), math.cos(turn)]]) @ (
        np.asarray(point) - ELLIPSE_CENTRE
    )
    a, b = SEMI_AXES

    def squared(t):
        return (a * math.cos(t) - local[0]) ** 2 + (b * math.sin(t) - local[1]) ** 2

    ts = np.linspace(-math.pi, math.pi, 3601)
    start = ts[np.argmin([squared(t) for t in ts])]
    found = minimize_scalar(squared, bounds=(start - 0.002, start + 0.002), method="bounded", options={"xatol": 1e-13})
    return math.sqrt(found.fun)


@pytest.mark.parametrize("start_x, tilt", [(0.0, 0.0), (0.25, 0.0), (0.1, TILT)])
def test_a_pin_falling_on_an_ellipse_meets_it_where_its_distance_reaches_the_radius(start_x, tilt):
    """The first impact's time is the free-fall time to the drop at which the centre's distance
    to the ellipse is the pin's radius (found here by root finding on that distance)."""
    report = simulated(falling_on_an_ellipse(start_x, tilt))
    drop = brentq(lambda s: distance_to_ellipse((start_x, -s), tilt) - RADIUS, 0.0, 0.3, xtol=1e-14)
    if start_x == 0.0 and tilt == 0.0:
        assert drop == pytest.approx(-ELLIPSE_CENTRE[1] - SEMI_AXES[1] - RADIUS, rel=1e-9)
    assert report["impacts"][0]["time"] == pytest.approx(math.sqrt(2 * drop / G), rel=1e-7)
    moreau = falling_on_an_ellipse(start_x, tilt)
    moreau["simulate"].update(scheme="moreau", step=1e-5)
    as_moreau(moreau["contacts"]["pairs"]["conjugate"])
    assert abs(simulated(moreau)["impacts"][0]["time"] - math.sqrt(2 * drop / G)) <= 1e-5


def test_the_state_derivatives_in_the_ellipses_numbers_equal_central_differences():
    """After the first impact on the tilted ellipse (off its axis), d(state)/d(semi-axis and
    angle) are the foot point's exact derivatives carried through the run."""
    pointers = ["/contacts/objects/egg/semi_axes/1", "/contacts/objects/egg/angle"]
    doc = falling_on_an_ellipse(0.1, TILT, until=0.2)
    doc["contacts"]["pairs"]["conjugate"]["normal"]["stiffness"] = 2.2656e9  # Table 2, as its number
    doc["simulate"]["sensitivities"] = pointers
    report = simulated(doc)
    assert report["impacts"] and report["impacts"][0]["time"] < 0.19
    doc["simulate"]["sensitivities"] = []
    for pointer, value in zip(pointers, (SEMI_AXES[1], TILT)):
        found = report["sensitivities"]["fields"][pointer]
        exact = np.array([values[name] for values in (found["coordinates"], found["velocities"]) for name in values])
        step = 1e-5 * value
        up, down = (end_state(simulated(variant(doc, pointer, sign * step))) for sign in (1, -1))
        differences = (up - down) / (2 * step)
        assert np.abs(differences).max() > 0
        np.testing.assert_allclose(exact, differences, atol=1e-5 * np.abs(differences).max(), err_msg=pointer)


def end_state(report: dict) -> np.ndarray:
    return np.array([values[-1] for part in ("coordinates", "velocities") for values in report[part].values()])


def test_a_quasi_static_contact_solve_refuses_a_circle_against_a_polygon_naming_where_it_is_taken():
    """Its rows need the exact distance, which the contact NLP has for circles, holes and
    half-planes only; the block rests the pin in a simulation, not here."""
    doc = falling_on_a_block("event_driven", 0.0)
    doc["contacts"]["pairs"]["conjugate"].update(normal={"law": "unilateral"}, friction=0)
    with pytest.raises(MechanismError) as caught:
        run_analysis(compile_mechanism(load_document(doc)), "contact", NewtonOptions())
    assert caught.value.pointer == "/document/contacts/pairs/conjugate/object"
    assert caught.value.problem == (
        "a quasi-static contact solve takes a circle site against circles, holes and "
        "half-planes; the polygon 'block' touches a circle in simulations (event_driven, "
        "moreau)"
    )
