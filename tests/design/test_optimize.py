"""Design optimization: the grasper of seed 002 Sec. 5.6.1 against Table 5.8, the gripper's
cross section, multipliers against re-optimization, and bad input."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
from conftest import EXAMPLES

from flexmech.models import MechanismError, compile_mechanism
from flexmech.models.documents.document import parse_document
from flexmech.service.design.optimize import optimize
from flexmech.service.design.problem import design_problem
from flexmech.service.solvers.equilibrium import solve_equilibrium

GRASPER = json.loads((EXAMPLES / "grasper_shape.json").read_text())
SECTIONS = json.loads((EXAMPLES / "gripper_sections.json").read_text())
# Table 5.8: optimal Fourier coefficients for 1, 2 and 3 terms, and the asked accuracy.
TABLE_5_8 = {1: ([1.3426], 2e-3), 2: ([1.1412, 0.7817], 2e-3), 3: ([1.0628, 0.7668, 0.5197], 1e-2)}


def grasper(terms: int, **changes) -> dict:
    data = copy.deepcopy(GRASPER)
    data["elements"]["link"]["shape"]["coefficients"] = [1.2] + [0.0] * (terms - 1)
    data["optimize"]["design"] = data["optimize"]["design"][:1] + [
        {"path": f"/elements/link/shape/coefficients/{k}", "lower": 0, "upper": 2} for k in range(terms)
    ]
    data["optimize"].update(changes)
    return data


def solve(data: dict, pointer: str = "/optimize"):
    doc = parse_document(data)
    mech = compile_mechanism(doc)
    return optimize(design_problem(mech, doc.optimize, pointer))


@pytest.fixture(scope="module")
def grasper_optima():
    return {n: solve(grasper(n)) for n in TABLE_5_8}


@pytest.mark.parametrize("terms", sorted(TABLE_5_8))
def test_grasper_reproduces_table_5_8_with_the_length_on_its_bound(grasper_optima, terms):
    result = grasper_optima[terms]
    published, tolerance = TABLE_5_8[terms]
    assert result.status == "optimal" and result.best.on_branch
    design = result.best.design
    found = [design[f"/elements/link/shape/coefficients/{k}"] for k in range(terms)]
    assert np.abs(np.subtract(found, published)).max() < tolerance
    assert design["/elements/link/length"] == pytest.approx(0.085, abs=1e-12)
    assert result.best.multipliers["design"][0] > 0  # the upper bound of L holds the optimum
    x_end = [c for c in result.best.constraints if c["output"] == "elements.link.x_end_undeformed"][0]
    assert x_end["value"] == pytest.approx(0.0508, abs=1e-9) and x_end["active"]


def test_grasper_forces_are_the_equilibrium_of_the_optimal_design_and_fall_with_more_terms(grasper_optima):
    """The objective is the tip force of the optimal design's equilibrium, solved on its own
    by Newton with load steps; more terms need less force, as in Table 5.8."""
    forces = {}
    for terms, result in grasper_optima.items():
        data = grasper(terms)
        mech = compile_mechanism(parse_document(data)).with_values(result.best.design)
        z = None
        for step in np.linspace(0.0, 0.0127, 9)[1:]:
            r = solve_equilibrium(mech.with_values({"/loads/push/dy": step}), guess=z)
            z = r.z
        forces[terms] = r.outputs()["reactions.tip.Fy"]
        assert result.best.objective == pytest.approx(forces[terms], rel=1e-9)
    assert forces[1] > forces[2] > forces[3]
    # With Table 5.7's EI the forces exceed the published 7.6227, 6.0119, 5.4298 N by the same
    # 4.5-4.9 %: the thesis' force scale (its EI) differs, not the optimal shapes.
    ratios = [forces[1] / 7.6227, forces[2] / 6.0119, forces[3] / 5.4298]
    assert all(1.04 < r < 1.05 for r in ratios)


def test_multiple_starts_agree_and_are_reported():
    result = solve(grasper(1, starts=3, seed=7))
    assert [s.start for s in result.starts] == [0, 1, 2]
    assert all(s.status == "optimal" for s in result.starts)
    assert len({round(s.design["/elements/link/shape/coefficients/0"], 8) for s in result.starts}) == 1
    assert len({tuple(s.design_start.values()) for s in result.starts}) == 3
    history = result.best.history
    assert len(history) == result.best.iterations + 1
    assert history[-1]["constraint_violation"] < 1e-8


def test_a_bound_multiplier_is_the_objective_change_per_unit_of_the_bound():
    """Raising the active upper bound of L by one unit changes the optimal force by minus its
    multiplier (central differences of re-optimization)."""
    base = solve(grasper(2, tolerance=1e-12))
    h = 1e-5
    moved = []
    for upper in (0.085 + h, 0.085 - h):
        data = grasper(2, tolerance=1e-12)
        data["optimize"]["design"][0]["upper"] = upper
        moved.append(solve(data).best.objective)
    slope = (moved[0] - moved[1]) / (2 * h)
    assert slope == pytest.approx(-base.best.multipliers["design"][0], rel=1e-5)


def test_gripper_cross_section_closes_at_the_force_with_the_stress_limit_active():
    result = solve(SECTIONS)
    assert result.status == "optimal"
    rows = {(c["output"], c["case"]): c for c in result.best.constraints}
    assert rows[("end_effector.x", "closing")]["value"] == pytest.approx(0.0, abs=1e-9)
    peak = max(rows[(f"elements.{e}.stress_max", "closing")]["value"] for e in "abcd")
    assert peak == pytest.approx(0.4, rel=1e-7)  # IPOPT relaxes bounds by 1e-8 relative
    assert all(c["value"] <= 0.4 * (1 + 1e-7) for c in rows.values() if c["upper"] == 0.4)
    outputs = result.outputs()
    assert outputs["closing"]["end_effector.x"] == pytest.approx(0.0, abs=1e-9)
    assert result.best.objective == pytest.approx(result.best.design["/sections/flexure/h"], rel=1e-12)


def test_an_infeasible_problem_returns_status_infeasible_with_the_least_violation():
    data = copy.deepcopy(SECTIONS)
    for c in data["optimize"]["constraints"]:
        if "upper" in c:
            c["upper"] = 0.05  # no section closes the gripper at 50 uN under 0.05 GPa
    result = solve(data)
    assert result.status == "infeasible"
    assert "no design satisfies the constraints and bounds" in result.message
    assert "end_effector.x (closing)" in result.message
    violated = [c for c in result.best.constraints if c["violation"] > 1e-6]
    assert violated


@pytest.mark.parametrize(
    "change, pointer, message",
    [
        (
            lambda o: o["design"][0].update(path="/sections/nope/h"),
            "/optimize/design/0/path",
            "'/sections/nope/h' is not a numeric field of this mechanism",
        ),
        (
            lambda o: o["design"][0].update(path="/elements/link/material"),
            "/optimize/design/0/path",
            "'/elements/link/material' is not a numeric field of this mechanism",
        ),
        (
            lambda o: o["design"][1].update(lower=1.5, upper=0.5),
            "/optimize/design/1/lower",
            "lower bound 1.5 is above the upper bound 0.5",
        ),
        (
            lambda o: o["objective"].update(output="reactions.tip.Fz"),
            "/optimize/objective/output",
            "unknown output 'reactions.tip.Fz' (outputs like it: reactions.base.Fx",
        ),
        (
            lambda o: o["constraints"][0].update(case="hot"),
            "/optimize/constraints/0/case",
            "unknown load case 'hot' (cases: nominal)",
        ),
    ],
)
def test_bad_design_problems_name_the_field(change, pointer, message):
    data = grasper(1)
    change(data["optimize"])
    with pytest.raises(MechanismError) as info:
        solve(data)
    assert info.value.pointer == pointer
    assert message in info.value.problem


def test_a_constraint_with_equals_and_bounds_is_refused_by_the_document():
    data = grasper(1)
    data["optimize"]["constraints"][0]["upper"] = 1.0
    with pytest.raises(MechanismError) as info:
        parse_document(data)
    assert info.value.pointer == "/optimize/constraints/0"
    assert "give equals, or lower and/or upper, not both" in info.value.problem


def test_a_stiffness_constraint_is_the_condensed_tangent_stiffness():
    """The thinnest flexures whose input stiffness K_T[y, y] reaches a target: the optimum
    meets it, and service.solvers.stiffness gives the same stiffness at the optimal design."""
    from flexmech.service.solvers.stiffness import tangent_stiffness

    data = json.loads((EXAMPLES / "gripper.json").read_text())
    data.pop("sweep")
    data["optimize"] = {
        "design": [{"path": "/sections/flexure/h", "lower": 0.002, "upper": 0.02}],
        "objective": {"output": "/sections/flexure/h"},
        "constraints": [{"output": "stiffness.input.y", "lower": 1000.0}],
    }
    result = solve(data)
    assert result.status == "optimal"
    mech = compile_mechanism(parse_document(data)).with_values(result.best.design)
    z = solve_equilibrium(mech).z
    kt = tangent_stiffness(mech, z)
    k = kt.coordinates.index("input.y")
    compliance = np.linalg.inv(kt.K)[k, k]
    assert 1 / compliance == pytest.approx(1000.0, rel=1e-7)
    assert result.best.constraints[0]["value"] == pytest.approx(1000.0, rel=1e-7)
    assert result.best.design["/sections/flexure/h"] > 0.002  # the bound does not hold it: the stiffness does
