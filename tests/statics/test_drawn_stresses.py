"""The stress drawn along every flexure and link (service.drawings.stresses, the families'
stress_along): the same numbers as each element's own stress outputs, the closed form of a
tip-loaded cantilever, and the material's allowable stress as the document gives it."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import ACTUATION, EXAMPLES

from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service import solve_equilibrium
from flexmech.service.drawings.drawing import mechanism_drawing

TARGET_FORCE = 77.035  # uN: the gripper closes (end effector at x = 0), seed 000 Sec. 5.1
SAME = 1e-9  # relative: one quantity computed twice from one state
LENGTH, WIDTH, THICKNESS, E = 100.0, 10.0, 2.0, 200.0  # mm, mm, mm, GPa


def solved_drawing(document, overrides=None):
    mech = compile_mechanism(load_document(document)).with_values(overrides or {})
    result = solve_equilibrium(mech)
    assert result.converged
    outputs = result.outputs()
    return mechanism_drawing(result.mechanism, result.z, outputs), outputs


def test_the_gripper_flexures_drawn_stresses_are_their_own_outputs():
    """Partial non-linear curved beams: the start section carries stress_start, the end section
    stress_end, and the largest drawn stress is stress_max, on all four flexures."""
    drawing, outputs = solved_drawing(EXAMPLES / "gripper.json", {ACTUATION: TARGET_FORCE})
    stresses = drawing["deformed"]["stresses"]
    assert drawing["units"]["stress"] == "GPa"
    assert sorted(stresses) == ["a", "b", "c", "d"]
    for name, along in stresses.items():
        assert len(along) == len(drawing["deformed"]["elements"][name])
        assert along[0] == pytest.approx(outputs[f"elements.{name}.stress_start"], rel=SAME)
        assert along[-1] == pytest.approx(outputs[f"elements.{name}.stress_end"], rel=SAME)
        assert max(along) == pytest.approx(outputs[f"elements.{name}.stress_max"], rel=SAME)
        assert min(along) >= 0


def test_exact_gripper_links_drawn_stresses_are_their_shooting_moments():
    """The exact model is a link by shooting: the moment M_end + (p_end - p) x n at its drawn
    samples is the moment it integrates, so the largest is its stress_max."""
    drawing, outputs = solved_drawing(EXAMPLES / "gripper_exact.json")
    for name, along in drawing["deformed"]["stresses"].items():
        assert max(along) == pytest.approx(outputs[f"elements.{name}.stress_max"], rel=1e-8)


def cantilever(discretization: str, force: float) -> dict:
    """A straight link clamped at `clamp`, a force across it at its free joint."""
    link = {"type": "link", "from": "clamp", "to": "tip", "length": LENGTH, "material": "steel", "section": "bar"}
    link.update({"discretization": "elements", "intervals": 8} if discretization == "elements" else {"intervals": 8})
    return {
        "units": {"length": "mm", "force": "N", "stress": "MPa", "angle": "deg"},
        "materials": {"steel": {"E": E * 1000, "stress_limit": "250 MPa"}},
        "sections": {"bar": {"b": WIDTH, "h": THICKNESS}},
        "bodies": {"clamp": {"fixed": True, "position": [0, 0]}, "tip": {"joint": True, "position": [LENGTH, 0]}},
        "elements": {"beam": link},
        "loads": {"F": {"type": "force", "body": "tip", "force": [0, force]}},
    }


@pytest.mark.parametrize("discretization", ["shooting", "elements"])
def test_a_tip_loaded_cantilever_is_stressed_most_at_its_clamp_as_the_closed_form_says(discretization):
    """sigma = F L c / I at the clamp, falling linearly to zero at the tip, for a load small
    enough that the beam stays straight (tip deflection 1e-5 of its length)."""
    inertia = WIDTH * THICKNESS**3 / 12
    force = 1e-5 * 3 * E * 1000 * inertia / LENGTH**2  # N: deflection F L^3 / 3EI = 1e-5 L
    drawing, outputs = solved_drawing(cantilever(discretization, force))
    along = np.asarray(drawing["deformed"]["stresses"]["beam"])
    closed_form = force * LENGTH * (THICKNESS / 2) / inertia  # MPa
    assert along[0] == pytest.approx(closed_form, rel=1e-4)
    assert along[-1] == pytest.approx(0.0, abs=1e-9 * closed_form)
    x = np.asarray(drawing["deformed"]["elements"]["beam"])[:, 0]
    assert along == pytest.approx(closed_form * (1 - x / LENGTH), rel=1e-4, abs=1e-4 * closed_form)
    assert along[0] == pytest.approx(outputs.get("elements.beam.stress_start", along[0]), rel=SAME)
    assert along[-1] == pytest.approx(outputs.get("elements.beam.stress_end", along[-1]), abs=1e-9 * closed_form)
    assert drawing["elements"][0]["stress_limit"] == pytest.approx(250.0)


def test_links_by_elements_drawn_stresses_are_their_end_stresses_under_large_deflection():
    """At a large deflection the ends' stresses are the reactions' (stress_start, stress_end),
    and the moment between follows the deformed line."""
    drawing, outputs = solved_drawing(cantilever("elements", 400.0))
    along = drawing["deformed"]["stresses"]["beam"]
    assert along[0] == pytest.approx(outputs["elements.beam.stress_start"], rel=1e-8)
    assert along[-1] == pytest.approx(outputs["elements.beam.stress_end"], abs=1e-8 * along[0])
    assert np.all(np.diff(along) < 0)  # a tip force: the moment falls from the clamp to the tip


def test_pins_springs_and_fibreless_sections_are_left_out():
    """A section without an outer fibre (the thesis cantilever's general section) tells no
    stress; the drawing then has none, and no limit."""
    drawing, _ = solved_drawing(EXAMPLES / "cantilever.json")
    assert "stresses" not in drawing["deformed"]
    assert "stress_limit" not in drawing["elements"][0]


def test_the_sections_example_gives_silicon_the_limit_it_optimizes_against():
    document = json.loads((EXAMPLES / "gripper_sections.json").read_text())
    assert document["materials"]["silicon"]["stress_limit"] == 0.4  # GPa, as its constraints
    drawing = mechanism_drawing(compile_mechanism(load_document(document)))
    assert {e["name"]: e["stress_limit"] for e in drawing["elements"]} == {n: 0.4 for n in "abcd"}


@pytest.mark.parametrize(
    ("limit", "message"),
    [
        (-0.4, "must be positive, got -0.4"),
        ("0 GPa", "must be positive, got 0 GPa"),
        ("3 mm", "'3 mm' is not a stress"),
    ],
)
def test_a_stress_limit_is_a_positive_stress(gripper_dict, limit, message):
    gripper_dict["materials"]["silicon"]["stress_limit"] = limit
    with pytest.raises(MechanismError) as error:
        load_document(gripper_dict)
    assert error.value.pointer == "/materials/silicon/stress_limit"
    assert message in error.value.problem


def test_a_stress_limit_out_of_range_is_named_where_it_is_drawn(gripper_dict):
    gripper_dict["materials"]["silicon"]["stress_limit"] = 1e300
    with pytest.raises(MechanismError) as error:
        mechanism_drawing(compile_mechanism(load_document(gripper_dict)))
    assert error.value.pointer == "/materials/silicon/stress_limit"
    assert "out of range" in error.value.problem
