"""Robust design against the etch (issue 51, acceptance 3): mean + k sigma and the first-order
yield inside the design NLP, their values equal to the first order of independent codes (the
tolerance analysis, equilibrium_sensitivities), their gradients exact (against central
differences of solved states), and the robust gripper's Monte Carlo yield above the nominal
design's."""

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
from flexmech.service.design.robust_nlp import tail_start
from flexmech.service.design.sensitivity import equilibrium_sensitivities
from flexmech.service.design.states import case_params, equilibria
from flexmech.service.solvers.newton import NewtonOptions

DOCUMENT = json.loads((EXAMPLES / "gripper_robust.json").read_text())
H, B, TIP = "/sections/flexure/h", "/sections/flexure/b", "end_effector.x"
SIGMA_H = 1e-4  # mm: the document's 0.1 um


def variant(objective: dict | None = None, constraint: dict | None = None) -> dict:
    """The example with another objective and/or first constraint."""
    document = copy.deepcopy(DOCUMENT)
    if objective is not None:
        document["optimize"]["objective"] = objective
    if constraint is not None:
        document["optimize"]["constraints"][0] = constraint
    return document


# The tip's mean - 2 sigma as high as it goes with 95 % of the parts meeting its spec (first order).
YIELD_95 = variant(
    objective={"output": TIP, "case": "closing", "sense": "maximize", "sigmas": 2},
    constraint={"output": "yield", "case": "closing", "lower": 0.95},
)


def closing(mech):
    """The mechanism under the closing case's 50 uN (the document's own load)."""
    return mech.with_values({"/loads/actuation/force/1": 50})


def tolerance_first_order(mech) -> dict:
    """The tolerance analysis' first order of the tip under 50 uN (mm): nominal, std and the
    first-order share meeting the spec."""
    report = run_analysis(closing(mech), "tolerance", NewtonOptions(), {"samples": 0, "outputs": [TIP]})
    entry = report["responses"][TIP]
    return {"nominal": entry["nominal"], "std": entry["first_order"]["std"], "share": entry["spec_share_first_order"]}


def start_point(problem):
    """The NLP's unknowns at the document's design: every case solved, every block S the solve of
    the NLP's own rows K S + R_p L = 0 (linear in S: one Newton step from S = 0)."""
    prepared, nlp = prepare(problem), design_nlp(problem)
    zs = [z for _, z in equilibria(problem, problem.start)]
    x = np.concatenate([problem.start / problem.scale, *zs, np.zeros(nlp.n_sensitivity)])
    blocks = slice(len(x) - nlp.n_sensitivity, len(x))
    rows = slice(nlp.n_residuals - nlp.n_sensitivity, nlp.n_residuals)
    jacobian = ca.Function("J", [nlp.x, nlp.P], [ca.jacobian(nlp.g, nlp.x)])
    _, g = nlp.evaluate(x, prepared.P)
    x[blocks] = -np.linalg.solve(np.asarray(jacobian(x, prepared.P))[rows, blocks], np.asarray(g).ravel()[rows])
    return prepared, nlp, x, np.asarray(jacobian(x, prepared.P))


def test_the_nlp_sigma_is_equilibrium_sensitivities_times_the_fields_sigma():
    """mean + 3 sigma as the NLP's constraint row holds it, from its own sensitivity unknowns,
    against nominal + 3 |dx/dh| 0.1 um of equilibrium_sensitivities at the same state."""
    mech = flexmech.load(DOCUMENT)
    problem = design_problem(mech, mech.document.optimize)
    prepared, nlp, x, _ = start_point(problem)
    _, g = nlp.evaluate(x, prepared.P)
    row = float(np.asarray(g).ravel()[nlp.n_residuals]) * prepared.constraint_scales[0]
    robust = row / mech.nd_per_doc("length")
    case = problem.case_names.index("closing")
    z = x[nlp.n_design + case * nlp.n_state : nlp.n_design + (case + 1) * nlp.n_state]
    sens = equilibrium_sensitivities(closing(mech), z, [H], [TIP])
    outputs = np.asarray(mech.graphs.outputs(z, case_params(problem, problem.start)[case])).ravel()
    nominal = outputs[mech.graphs.output_names.index(TIP)] / mech.nd_per_doc("length")
    sigma = abs(sens.matrix[0, 0]) * SIGMA_H
    assert sigma > 0.01  # mm: the etch moves the tip by more than its 5 um band
    assert robust == pytest.approx(nominal + 3 * sigma, rel=1e-8)
    assert nominal + 3 * sigma == pytest.approx(
        (lambda first: first["nominal"] + 3 * first["std"])(tolerance_first_order(mech)), rel=1e-8
    )


def reduced_gradient(problem, row: int | None) -> np.ndarray:
    """d(objective or constraint row)/d(design) in its document unit per design unit, the cases'
    states and the blocks S following through the NLP's equality rows."""
    prepared, nlp, x, J = start_point(problem)
    equalities, design = slice(0, nlp.n_residuals), slice(0, nlp.n_design)
    followers = slice(nlp.n_design, len(x))
    assert J.shape[1] - nlp.n_design == nlp.n_residuals  # no modes: the followers are square
    dw_dd = -np.linalg.solve(J[equalities, followers], J[equalities, design])
    if row is None:
        grad = np.asarray(ca.Function("f_x", [nlp.x, nlp.P], [ca.gradient(nlp.f, nlp.x)])(x, prepared.P)).ravel()
        scale, ref = prepared.objective_scale, problem.objective
    else:
        grad, scale, ref = J[nlp.n_residuals + row], prepared.constraint_scales[row], problem.constraints[row].output
    reduced = grad[design] + grad[followers] @ dw_dd
    return reduced * scale / problem.output_factor(ref) / problem.scale


@pytest.mark.parametrize(
    "document, row, of",
    [
        (DOCUMENT, 0, lambda first: first["nominal"] + 3 * first["std"]),
        (YIELD_95, None, lambda first: first["nominal"] - 2 * first["std"]),
        (YIELD_95, 0, lambda first: np.log(first["share"])),
    ],
    ids=["constraint mean + 3 sigma", "objective mean - 2 sigma", "yield constraint (its ln)"],
)
def test_robust_rows_have_exact_gradients(document, row, of):
    """The NLP's reduced derivatives by h and b against central differences of the tolerance
    analysis' first order at solved states (an independent code)."""
    mech = flexmech.load(document)
    problem = design_problem(mech, mech.document.optimize)
    gradient = reduced_gradient(problem, row)
    for k, (path, step) in enumerate(((H, 1e-6), (B, 1e-6))):
        value = mech.value(path)
        ahead, behind = (of(tolerance_first_order(mech.with_values({path: value + s}))) for s in (step, -step))
        assert gradient[k] == pytest.approx((ahead - behind) / (2 * step), rel=1e-6), path


def test_the_robust_design_yields_more_parts_than_the_nominal_one():
    """1000 seeded samples each: a yield's standard error is at most 1.6 % (at 50 %)."""
    found = designs()
    reports = yields(found, samples=1000, seed=11)
    nominal, robust = (reports[label]["yield"] for label in ("nominal", "robust"))
    assert nominal["monte_carlo"] == pytest.approx(0.5, abs=4 * nominal["standard_error"])  # on the bound
    assert robust["monte_carlo"] > 0.99 > nominal["monte_carlo"] + 10 * nominal["standard_error"]
    tip = reports["robust"]["responses"][TIP]
    assert tip["nominal"] + 3 * tip["first_order"]["std"] == pytest.approx(0.005, abs=1e-7)  # its constraint, active


def test_a_yield_constraint_holds_at_its_optimum_and_the_report_says_so():
    mech = flexmech.load(YIELD_95)
    result = optimize(design_problem(mech, mech.document.optimize))
    best = result.best
    assert best is not None and best.status == "optimal"
    assert best.constraints[0]["value"] == pytest.approx(0.95, abs=1e-6)  # the yield itself, not its ln
    objective, share = result.summary()["robust"]
    assert share["of"] == "constraints/0" and share["yield"] == pytest.approx(0.95, abs=1e-6)
    report = run_analysis(
        closing(mech.with_values(best.design)), "tolerance", NewtonOptions(), {"samples": 1000, "seed": 5}
    )
    first = report["responses"][TIP]
    assert share["specs"][TIP]["sigma"] == pytest.approx(first["first_order"]["std"], rel=1e-8)
    assert objective["of"] == "objective" and objective["sigma"] == pytest.approx(first["first_order"]["std"], rel=1e-8)
    assert best.objective == objective["mean_minus_k_sigma"] == pytest.approx(first["nominal"] - 2 * objective["sigma"])
    assert report["yield"]["monte_carlo"] == pytest.approx(0.95, abs=4 * report["yield"]["standard_error"])


def test_the_report_gives_nominal_sigma_and_mean_plus_k_sigma():
    mech = flexmech.load(DOCUMENT)
    problem = design_problem(mech, mech.document.optimize)
    prepared, nlp, x, _ = start_point(problem)
    from flexmech.service.design.robust_report import robust_report

    (entry,) = robust_report(problem, x)
    first = tolerance_first_order(mech)
    assert entry["of"] == "constraints/0" and entry["unit"] == "mm" and entry["sigmas"] == 3
    assert entry["nominal"] == pytest.approx(first["nominal"], rel=1e-9)
    assert entry["sigma"] == pytest.approx(first["std"], rel=1e-8)
    assert entry["mean_plus_k_sigma"] == pytest.approx(first["nominal"] + 3 * first["std"], rel=1e-8)
    assert entry["mean_minus_k_sigma"] == pytest.approx(first["nominal"] - 3 * first["std"], rel=1e-8)
    zs = np.split(x[nlp.n_design : nlp.n_states], nlp.n_cases)
    start = tail_start(problem, nlp, prepared.P, zs, case_params(problem, problem.start))
    assert start == pytest.approx(x[nlp.n_states :], rel=1e-8, abs=1e-14)  # the numeric solve is the NLP's rows'


@pytest.mark.parametrize(
    "change, pointer, words",
    [
        (lambda d: d.pop("tolerances"), "/optimize/constraints/0/sigmas", "needs the document's tolerances section"),
        (
            lambda d: d["optimize"]["objective"].update(output=TIP, case="closing", sigmas=1) or d.pop("tolerances"),
            "/optimize/objective/sigmas",
            "needs the document's tolerances section",
        ),
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
        (
            lambda d: (
                d["optimize"]["constraints"].append({"output": "yield", "case": "closing", "lower": 0.9}),
                d["tolerances"]["specs"].update({"/loads/actuation/force/1": {"max": 80}}),
            )[0],
            "/tolerances/specs/~1loads~1actuation~1force~11",
            "is not an output",
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
