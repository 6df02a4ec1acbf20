"""Links by displacement-based elements (models.beams.link_fe): the accuracy order of the
discretization over three resolutions against Frisch-Fay's elastica, agreement with the
shooting solution of the same link (with shear and axial strain, pinned and curved), and
the stationarity of their energy form being their residual form."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from elastica_oracles import cantilever_tip

from flexmech.models import compile_mechanism, load_document
from flexmech.service.solvers.energy import minimize_energy
from flexmech.service.solvers.equilibrium import NewtonOptions, solve_equilibrium

TIGHT = NewtonOptions(tol_residual=1e-13, tol_step=1e-13)
E, B, H, LENGTH = 2e11, 0.01, 0.001, 0.1
EI = E * B * H**3 / 12


def cantilever(discretization: str, intervals: int, degree: int = 3, force=(0.0, 60.0), **link) -> dict:
    """A straight steel strip clamped at the origin, its free end a body under a dead force."""
    element = {
        "type": "link",
        "from": "ground",
        "to": "tip",
        "length": LENGTH,
        "material": "steel",
        "section": "strip",
        "discretization": discretization,
        "intervals": intervals,
        **link,
    }
    element.update({"degree": degree} if discretization == "elements" else {"order": 12})
    return {
        "units": {"length": "m", "force": "N", "angle": "rad"},
        "materials": {"steel": {"E": E, "nu": 0.3}},
        "sections": {"strip": {"b": B, "h": H}},
        "bodies": {"ground": {"fixed": True, "position": [0, 0]}, "tip": {"position": [LENGTH, 0]}},
        "elements": {"L": element},
        "loads": {"F": {"type": "force", "body": "tip", "force": list(force)}},
    }


def tip(document: dict, energy: bool = False) -> np.ndarray:
    mech = compile_mechanism(load_document(document))
    result = minimize_energy(mech) if energy else solve_equilibrium(mech, TIGHT)
    assert result.converged, result.message
    out = result.outputs()
    return np.array([out["elements.L.x_end"], out["elements.L.y_end"], out["elements.L.angle_end"]])


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_the_error_falls_as_h_to_twice_the_degree(degree):
    """Tip position errors against Frisch-Fay (F L^2 / EI = 3.6, tip angle 61 deg) at 4, 8
    and 16 elements: each halving divides the error by 2^(2 degree) (within 0.3 in the order)."""
    exact = np.array(cantilever_tip(EI, LENGTH, 60.0)[:2])
    errors = [np.abs(tip(cantilever("elements", n, degree))[:2] - exact).max() / LENGTH for n in (4, 8, 16)]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 2 * degree) < 0.3), (errors, orders)
    if degree == 3:
        assert errors[-1] < 1e-10


THICK = {
    "E": 2.6e9,
    "b": 0.0095,
    "h": 0.012,
    "L": 0.057,
}  # a short thick nylon finger: shear is 3 % of the tip deflection


def thick_finger(discretization: str, intervals: int, shape=None, start="clamped", **link) -> dict:
    doc = cantilever(discretization, intervals, start=start, shear=True, axial=True, **link)
    doc["materials"]["steel"] = {"E": THICK["E"], "nu": 0.4}
    doc["sections"]["strip"] = {"b": THICK["b"], "h": THICK["h"]}
    element = doc["elements"]["L"]
    element["length"] = THICK["L"]
    if shape is not None:
        element["shape"] = shape
    if start == "pinned":  # a pinned start needs a moment-free end held: pin the end on a slider-free body
        doc["loads"]["F"] = {"type": "force", "body": "tip", "force": [-300.0, 150.0]}
        doc["bodies"]["tip"]["position"] = [THICK["L"], 0]
    else:
        doc["loads"]["F"]["force"] = [-200.0, 600.0]
    return doc


@pytest.mark.parametrize("case", ["straight", "arc"])
def test_the_contact_free_state_equals_the_shooting_solution(case):
    """A thick finger with shear and axial strain, straight or initially an arc, under a large
    oblique tip force: the minimum of the energy (IPOPT) with 16 cubic elements and the
    shooting solution (16 intervals, order 12) agree to 1e-8 of the length at the tip; shear
    matters here (it moves the tip by far more than that)."""
    shape = None if case == "straight" else {"type": "arc", "angle": 0.0, "sweep": 0.6}
    doc_shoot, doc_fe = thick_finger("shooting", 16, shape), thick_finger("elements", 16, shape)
    if shape is not None:  # the arc ends elsewhere: put the tip body there
        end = THICK["L"] / 0.6 * np.array([np.sin(0.6), 1 - np.cos(0.6)])
        for doc in (doc_shoot, doc_fe):
            doc["bodies"]["tip"]["position"] = end.tolist()
    shooting, elements = tip(doc_shoot), tip(doc_fe, energy=True)
    assert np.abs(elements[:2] - shooting[:2]).max() / THICK["L"] < 1e-8
    assert abs(elements[2] - shooting[2]) < 1e-8
    no_shear = thick_finger("elements", 16, shape)
    no_shear["elements"]["L"]["shear"] = False
    if shape is not None:
        no_shear["bodies"]["tip"]["position"] = doc_fe["bodies"]["tip"]["position"]
    assert np.abs(tip(no_shear)[:2] - shooting[:2]).max() / THICK["L"] > 1e-4


def test_the_gradient_of_the_potential_is_the_residual_of_a_link_by_elements():
    """Pinned start, shear and axial strain: at a deformed state that is no equilibrium, the
    residual form's rows are the gradient of the Lagrangian of the energy form (z assembled by
    EnergyForm.to_state)."""
    doc = thick_finger("elements", 3, start="pinned")
    doc["bodies"]["tip"]["angle"] = 0.2
    mech = compile_mechanism(load_document(doc))
    form, p = mech.graphs.energy_form, mech.p()
    n, m = len(form.unknowns), form.n_multipliers
    assert n + m == mech.n_free
    x = ca.SX.sym("x", n)
    lagrangian_parts = ca.Function(
        "parts",
        [x],
        [ca.gradient(form.potential(x, p), x), ca.jacobian(form.equalities(x, p), x), form.equalities(x, p)],
    )
    rng = np.random.default_rng(5)
    x0, lam = rng.normal(scale=0.05, size=n), rng.normal(scale=0.5, size=m)
    gradient, J, g = (np.asarray(a) for a in lagrangian_parts(x0))
    z = form.to_state(x0, lam)
    R = np.asarray(mech.graphs.residual(z, p)).ravel()
    expected_x = gradient.ravel() + J.T @ lam
    assert np.abs(R).max() > 1e-2
    np.testing.assert_allclose(R[list(form.x_in_state)], expected_x, atol=1e-10 * np.abs(R).max())
    np.testing.assert_allclose(R[list(form.multipliers_in_state)], g.ravel(), atol=1e-12)
