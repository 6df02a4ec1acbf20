"""Sensitivities by the implicit function theorem against central finite differences."""

from __future__ import annotations

import copy
import json

import pytest
from conftest import ACTUATION, EXAMPLES

from flexmech.models import compile_mechanism, load_document
from flexmech.models.documents.document import parse_document
from flexmech.service.design.optimize import prepare, run_start
from flexmech.service.design.problem import design_problem
from flexmech.service.design.sensitivity import equilibrium_sensitivities, optimum_sensitivities
from flexmech.service.solvers.equilibrium import solve_equilibrium
from flexmech.service.solvers.sweep import solve_for_target

H_PATH, E_PATH = "/sections/flexure/h", "/materials/silicon/E"


def central(f, x: float, h: float) -> float:
    return (f(x + h) - f(x - h)) / (2 * h)


@pytest.fixture(scope="module")
def gripper_pnl_mech():
    return compile_mechanism(load_document(EXAMPLES / "gripper.json"), model="partial_nonlinear")


def test_closing_force_sensitivities_to_h_and_E_match_finite_differences(gripper_pnl_mech):
    mech = gripper_pnl_mech
    found = solve_for_target(mech, ACTUATION, "end_effector.x", 0.0)
    closed = found.equilibrium.mechanism
    sens = equilibrium_sensitivities(
        closed,
        found.equilibrium.z,
        [H_PATH, E_PATH],
        [ACTUATION, "end_effector.y"],
        target=(ACTUATION, "end_effector.x"),
    )
    assert sens.outputs == [ACTUATION, "end_effector.y"]
    assert sens.units[0] == ["uN/mm", "uN/GPa"]

    def closing_force(path):
        return lambda v: solve_for_target(mech.with_values({path: v}), ACTUATION, "end_effector.x", 0.0).value

    h, E = mech.value(H_PATH), mech.value(E_PATH)
    assert sens.matrix[0, 0] == pytest.approx(central(closing_force(H_PATH), h, h * 1e-4), rel=1e-6)
    assert sens.matrix[0, 1] == pytest.approx(central(closing_force(E_PATH), E, E * 1e-4), rel=1e-6)
    # The closing force is proportional to E (the kinematics do not depend on it) and, for a
    # fixed arc, to h^3 in the flexures' stiffness: dF/dE = F / E exactly.
    assert sens.matrix[0, 1] == pytest.approx(found.value / E, rel=1e-9)


def test_link_tip_position_sensitivities_to_shape_coefficients_match_finite_differences():
    data = json.loads((EXAMPLES / "cantilever.json").read_text())
    data["elements"]["beam"]["shape"] = {"type": "fourier_sine", "coefficients": [0.3, -0.2], "omega": 3.14159}
    mech = compile_mechanism(parse_document(data))
    paths = ["/elements/beam/shape/coefficients/0", "/elements/beam/shape/coefficients/1"]
    result = solve_equilibrium(mech)
    sens = equilibrium_sensitivities(mech, result.z, paths, ["tip.x", "tip.y", "elements.beam.rotation_end"])

    def output(path, name):
        def f(v):
            r = solve_equilibrium(mech.with_values({path: v}), guess=result.z)
            return r.outputs()[name]

        return f

    for j, path in enumerate(paths):
        for i, name in enumerate(sens.outputs):
            fd = central(output(path, name), mech.value(path), 1e-4)
            assert sens.matrix[i, j] == pytest.approx(fd, rel=1e-6, abs=1e-9 * abs(sens.matrix[:, j]).max())


@pytest.fixture(scope="module")
def sections_optimum():
    data = json.loads((EXAMPLES / "gripper_sections.json").read_text())
    data["optimize"]["tolerance"] = 1e-12
    return data


def _optimum(data, changes=None):
    data = copy.deepcopy(data)
    doc = parse_document(data)
    mech = compile_mechanism(doc).with_values(changes or {})
    problem = design_problem(mech, doc.optimize)
    prepared = prepare(problem)
    return prepared, run_start(prepared, 0)


def test_optimum_sensitivities_with_strictly_inactive_inequalities_match_reoptimization(sections_optimum):
    """Seven of the nine stress limits are strictly inactive at the optimum (IPOPT leaves them
    tiny multipliers); only the active set enters the KKT system, and the sensitivities of the
    optimal section equal central differences of re-optimized designs."""
    prepared, best = _optimum(sections_optimum)
    inactive = [c for c in best.constraints if not c["active"]]
    assert len(inactive) == 7
    assert all(c["upper"] - c["value"] > 0.05 and abs(c["multiplier"]) < 1e-9 for c in inactive)
    radius = "/elements/d/radius"
    sens = optimum_sensitivities(prepared, best, [E_PATH, radius])
    mech = prepared.problem.mechanism
    for j, (path, step) in enumerate(((E_PATH, 1e-3), (radius, 1e-5))):
        value = mech.value(path)
        plus = _optimum(sections_optimum, {path: value + step})[1]
        minus = _optimum(sections_optimum, {path: value - step})[1]
        for i, name in enumerate(prepared.problem.paths):
            fd = (plus.design[name] - minus.design[name]) / (2 * step)
            assert sens.matrix[i, j] == pytest.approx(fd, rel=1e-6)
        assert sens.matrix[-1, j] == pytest.approx((plus.objective - minus.objective) / (2 * step), rel=1e-6)
    # The stress limit fixes h: sigma ~ E h (curvature set by the kinematics), so h* ~ 1/E.
    h = best.design[H_PATH]
    assert sens.matrix[0, 0] == pytest.approx(-h / mech.value(E_PATH), rel=1e-8)


def test_sensitivities_name_bad_fields(gripper_pnl_mech):
    from flexmech.models import MechanismError

    z = solve_equilibrium(gripper_pnl_mech).z
    with pytest.raises(MechanismError) as info:
        equilibrium_sensitivities(gripper_pnl_mech, z, ["/sections/flexure/q"], ["end_effector.x"])
    assert info.value.pointer == "/parameters/0" and "not a numeric field" in info.value.problem
    with pytest.raises(MechanismError) as info:
        equilibrium_sensitivities(gripper_pnl_mech, z, [H_PATH], ["end_effector.z"])
    assert info.value.pointer == "/outputs/0" and info.value.problem == "unknown output 'end_effector.z'"
