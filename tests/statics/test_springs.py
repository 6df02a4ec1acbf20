"""The spring family against closed forms: a nonlinear law against finite differences and the
integral of its expression, its named parameters as numeric fields, and its errors."""

from __future__ import annotations

import math

import pytest

from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service.solvers.equilibrium import NewtonOptions, solve_equilibrium

TIGHT = NewtonOptions(tol_residual=1e-13, tol_step=1e-12)


def _torsion_document(law: dict, moment: float) -> dict:
    """A body free to turn about its reference point (its translation prescribed), held by a
    torsional spring, under a moment (units: m, N, rad)."""
    return {
        "units": {"length": "m", "force": "N", "angle": "rad"},
        "bodies": {"ground": {"fixed": True, "position": [0, 0]}, "arm": {"position": [0, 0]}},
        "elements": {"coil": {"type": "spring", "kind": "torsional", "from": "ground", "to": "arm", **law}},
        "loads": {
            "twist": {"type": "moment", "body": "arm", "moment": moment},
            "axle": {"type": "displacement", "body": "arm", "dx": 0, "dy": 0},
        },
    }


LAW = "k * x + c * sinh(x / a)"
PARAMETERS = {"k": 2.0, "c": 0.5, "a": 0.3}


def law(x: float) -> float:
    return PARAMETERS["k"] * x + PARAMETERS["c"] * math.sinh(x / PARAMETERS["a"])


def test_a_nonlinear_law_matches_finite_differences_of_its_expression():
    mech = compile_mechanism(load_document(_torsion_document({"law": LAW, "parameters": PARAMETERS}, 3.0)))
    result = solve_equilibrium(mech, TIGHT)
    out = result.outputs()
    x = out["elements.coil.rotation"]
    assert law(x) == pytest.approx(3.0, rel=1e-12)  # the spring holds the moment
    from flexmech.service.solvers.stiffness import tangent_stiffness

    (stiffness,) = tangent_stiffness(mech, result.z).K.ravel()  # arm.angle alone: N m per rad
    h = 1e-6
    assert stiffness == pytest.approx((law(x + h) - law(x - h)) / (2 * h), rel=1e-8)
    # Its energy is the integral of the law: k x^2 / 2 + c a (cosh(x / a) - 1).
    k, c, a = PARAMETERS.values()
    assert out["elements.coil.energy"] == pytest.approx(k * x**2 / 2 + c * a * (math.cosh(x / a) - 1), rel=1e-12)


def test_the_law_parameters_are_numeric_fields():
    mech = compile_mechanism(load_document(_torsion_document({"law": LAW, "parameters": PARAMETERS}, 3.0)))
    stiffer = solve_equilibrium(mech.with_values({"/elements/coil/parameters/k": 4.0}), TIGHT).outputs()
    PARAMETERS_4 = dict(PARAMETERS, k=4.0)
    x = stiffer["elements.coil.rotation"]
    assert PARAMETERS_4["k"] * x + PARAMETERS_4["c"] * math.sinh(x / PARAMETERS_4["a"]) == pytest.approx(3.0, rel=1e-12)


@pytest.mark.parametrize(
    "law, pointer, message",
    [
        ({"law": "k * x + y", "parameters": {"k": 1}}, "/elements/coil/law", "the name 'y' is not allowed"),
        ({"law": "x", "parameters": {"pi": 1}}, "/elements/coil/parameters/pi", "'pi' cannot name a parameter"),
        ({"law": "x", "stiffness": 3}, "/elements/coil", "give either 'stiffness' or 'law'"),
        ({"stiffness": -1}, "/elements/coil/stiffness", "must not be negative"),
    ],
)
def test_bad_spring_laws_name_the_field(law, pointer, message):
    with pytest.raises(MechanismError) as info:
        compile_mechanism(load_document(_torsion_document(law, 1.0)))
    assert info.value.pointer == pointer and message in info.value.problem
