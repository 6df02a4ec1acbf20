"""Robust design against the etch (issue 51, acceptance 3): mean + k sigma and the first-order
yield inside the design NLP, their values equal to the tolerance analysis' first order, their
gradients exact (against central differences of solved states), and the robust gripper's Monte
Carlo yield above the nominal design's."""

from __future__ import annotations

import copy
import json

import casadi as ca
import numpy as np
import pytest
from conftest import EXAMPLES

import flexmech
from flexmech.examples.robust_gripper import designs, yields
from flexmech.models import MechanismError
from flexmech.service.analysis import run_analysis
from flexmech.service.design.nlp import design_nlp
from flexmech.service.design.optimize import optimize, prepare
from flexmech.service.design.problem import design_problem
from flexmech.service.design.robust import robust_value
from flexmech.service.solvers.equilibrium import solve_equilibrium
from flexmech.service.solvers.newton import NewtonOptions

DOCUMENT = json.loads((EXAMPLES / "gripper_robust.json").read_text())
H, TIP = "/sections/flexure/h", "end_effector.x"


def closing(mech):
    """The mechanism under the closing case's 50 uN (the document's own load)."""
    return mech.with_values({"/loads/actuation/force/1": 50})


def first_order(mech) -> tuple[float, float]:
    """(nominal, sigma) of the tip under 50 uN by the tolerance analysis (mm)."""
    report = run_analysis(closing(mech), "tolerance", NewtonOptions(), {"samples": 0, "outputs": [TIP]})
    entry = report["responses"][TIP]
    return entry["nominal"], entry["first_order"]["std"]


@pytest.fixture(scope="module")
def problem():
    mech = flexmech.load(DOCUMENT)
    return design_problem(mech, mech.document.optimize)


def test_mean_plus_three_sigma_is_the_tolerance_analysis_first_order(problem):
    ref = problem.constraints[0].output
    assert ref.sigmas == 3.0 and ref.name == TIP
    mech = closing(problem.mechanism.with_values({H: 0.0061}))
    state = solve_equilibrium(mech)
    value = robust_value(mech.structure, ref, state.z, mech.p()) / mech.nd_per_doc("length")
    nominal, sigma = first_order(mech)
    assert value == pytest.approx(nominal + 3 * sigma, rel=1e-9)


def test_the_robust_constraint_has_exact_gradients(problem):
    """The NLP's reduced derivative of mean + 3 sigma by h (the state following through
    K dz = -R_d dd) against central differences of solved states."""
    prepared = prepare(problem)
    nlp = design_nlp(problem)
    x0 = np.concatenate([problem.start / problem.scale, np.zeros(nlp.n_state * nlp.n_cases)])
    closing_case = problem.case_names.index("closing")
    state = solve_equilibrium(closing(problem.mechanism))
    x0[nlp.n_design + closing_case * nlp.n_state : nlp.n_design + (closing_case + 1) * nlp.n_state] = state.z
    jacobian = ca.Function("J", [nlp.x, nlp.P], [ca.jacobian(nlp.g, nlp.x)])
    J = np.asarray(jacobian(x0, prepared.P))
    rows = slice(closing_case * nlp.n_state, (closing_case + 1) * nlp.n_state)
    columns = slice(nlp.n_design + closing_case * nlp.n_state, nlp.n_design + (closing_case + 1) * nlp.n_state)
    row = nlp.n_residuals  # the robust constraint: the first after the residuals
    dz_dd = -np.linalg.solve(J[rows, columns], J[rows, : nlp.n_design])
    reduced = J[row, : nlp.n_design] + J[row, columns] @ dz_dd
    per_h = reduced[0] * prepared.constraint_scales[0] / problem.scale[0] / problem.mechanism.nd_per_doc("length")
    step = 1e-6  # mm
    values = []
    for h in (problem.start[0] + step, problem.start[0] - step):
        nominal, sigma = first_order(problem.mechanism.with_values({H: h}))
        values.append(nominal + 3 * sigma)
    assert per_h == pytest.approx((values[0] - values[1]) / (2 * step), rel=1e-6)


def test_the_robust_design_yields_more_parts_than_the_nominal_one():
    found = designs()
    reports = yields(found, samples=4000, seed=11)
    nominal, robust = (reports[label]["yield"] for label in ("nominal", "robust"))
    assert nominal["monte_carlo"] == pytest.approx(0.5, abs=4 * nominal["standard_error"])  # on the bound
    assert robust["monte_carlo"] > 0.99 > nominal["monte_carlo"] + 10 * nominal["standard_error"]
    tip = reports["robust"]["responses"][TIP]
    assert tip["nominal"] + 3 * tip["first_order"]["std"] == pytest.approx(0.005, abs=1e-7)  # its constraint, active


def test_a_yield_constraint_holds_at_its_optimum():
    document = copy.deepcopy(DOCUMENT)
    document["optimize"]["constraints"][0] = {"output": "yield", "case": "closing", "lower": 0.95}
    mech = flexmech.load(document)
    best = optimize(design_problem(mech, mech.document.optimize)).best
    assert best is not None and best.status == "optimal"
    report = run_analysis(
        closing(mech.with_values(best.design)),
        "tolerance",
        NewtonOptions(),
        {"samples": 2000, "seed": 5, "outputs": [TIP]},
    )
    assert report["responses"][TIP]["spec_share_first_order"] == pytest.approx(0.95, abs=1e-6)
    assert report["yield"]["monte_carlo"] == pytest.approx(0.95, abs=4 * report["yield"]["standard_error"])


@pytest.mark.parametrize(
    "change, pointer, words",
    [
        (lambda d: d.pop("tolerances"), "/optimize/constraints/0/sigmas", "needs the document's tolerances section"),
        (
            lambda d: d["optimize"]["constraints"][0].update(upper=None, equals=0.0),
            "/optimize/constraints/0/sigmas",
            "cannot equal a value",
        ),
        (
            lambda d: d["optimize"]["objective"].update(sigmas=2),
            "/optimize/objective/sigmas",
            "not for '/sections/flexure/h'",
        ),
        (
            lambda d: (
                d["optimize"]["constraints"].append({"output": "yield", "case": "closing", "lower": 0.9}),
                d["tolerances"].update(specs={}),
            )[0],
            "/optimize/constraints/9/output",
            "a yield needs specs on outputs",
        ),
    ],
)
def test_robust_requests_that_cannot_be_met_name_their_field(change, pointer, words):
    document = copy.deepcopy(DOCUMENT)
    change(document)
    document["optimize"]["constraints"][0] = {
        k: v for k, v in document["optimize"]["constraints"][0].items() if v is not None
    }
    mech = flexmech.load(document)
    with pytest.raises(MechanismError) as info:
        design_problem(mech, mech.document.optimize)
    assert info.value.pointer == pointer and words in info.value.problem
