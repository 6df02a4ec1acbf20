"""The seed 000 gripper closing dynamically on a part held by a spring
(examples/gripper_grasp_dynamics.json): exact curved beams by elements with silicon's density,
Lankarani-Nikravesh contact with Ambrosio's friction between the part and a pad at the end
effector, its onset located. It strikes the part, then the mass-proportional damping settles it
on the equilibrium solve of the same document (which takes the law's elastic part; the
regularized friction vanishes at rest)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from flexmech.models import compile_mechanism, load_document
from flexmech.service.analysis import run_analysis
from flexmech.service.solvers.newton import NewtonOptions

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def analysed(doc: dict, analysis: str) -> dict:
    return run_analysis(compile_mechanism(load_document(doc)), analysis, NewtonOptions())


def test_the_exact_curved_beams_by_elements_stand_where_the_shooting_ones_do():
    """The exact model by 8 cubic elements against its shooting (the shipped gripper_exact):
    the end effector to 1e-7 mm."""
    shooting = json.loads((EXAMPLES / "gripper_exact.json").read_text())
    elements = json.loads((EXAMPLES / "gripper_exact.json").read_text())
    for beam in elements["elements"].values():
        beam["discretization"] = "elements"
    a, b = analysed(shooting, "equilibrium"), analysed(elements, "equilibrium")
    for coordinate in ("end_effector.x", "end_effector.y"):
        assert b["outputs"][coordinate] == pytest.approx(a["outputs"][coordinate], abs=1e-7)


def test_the_gripper_strikes_the_part_and_settles_on_the_equilibrium_solve():
    doc = json.loads((EXAMPLES / "gripper_grasp_dynamics.json").read_text())
    static = analysed(doc, "equilibrium")
    held = static["outputs"]["contacts.grip.normal_force"]
    assert static["output_units"]["contacts.grip.normal_force"] == "uN"
    assert 1 < held < 60  # the part takes a part of the 60 uN actuation
    run = analysed(doc, "simulate")
    assert run["status"] == "finished", run["message"]
    forces = np.array(run["outputs"]["contacts.grip.normal_force"])
    assert forces[0] == 0 and forces.max() > 5 * held  # it closes from open and strikes
    assert forces[-1] == pytest.approx(held, rel=1e-6)
    indentation = np.array(run["outputs"]["contacts.grip.indentation"])
    assert np.abs(indentation).min() < 1e-12  # mm: a state on the onset
    assert run["energies"]["contact_damping_work"][-1] < 0 and run["energies"]["friction_work"][-1] < 0
    assert run["energy_balance_error"] < 5e-3  # generalized-alpha's own dissipation (rho_inf 0.5) is not in it
    assert run["outputs"]["bodies.part.y"][-1] == pytest.approx(static["outputs"]["bodies.part.y"], abs=1e-7)  # mm


def test_exact_curved_beams_by_elements_are_priced_as_elements():
    """The service's costing (service.costs) prices an exact beam by elements as a link by
    elements, intervals x (degree + 2)^2, not as shooting's intervals x order^2."""
    from flexmech.service.costs import link_work

    doc = json.loads((EXAMPLES / "gripper_grasp_dynamics.json").read_text())
    beams = [name for name, element in doc["elements"].items() if element["type"] == "curved_beam"]
    assert dict(link_work(load_document(doc), None)) == {name: 4 * 5**2 for name in beams}
    for name in beams:
        doc["elements"][name]["discretization"] = "shooting"
    assert dict(link_work(load_document(doc), None)) == {name: 4 * 8**2 for name in beams}
