"""The energy form of mechanisms of rigid bodies, springs and joints: its stationarity is the
residual form (checked at a deformed state that is no equilibrium), its minimum by IPOPT is
Newton's equilibrium, and structures whose elements have no energy form are refused."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from conftest import EXAMPLES
from mechanisms import chain, four_bar

from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service.solvers.energy import minimize_energy
from flexmech.service.solvers.equilibrium import NewtonOptions, solve_equilibrium

TIGHT = NewtonOptions(tol_residual=1e-13, tol_step=1e-12)


@pytest.mark.parametrize("document", [four_bar, chain], ids=["four_bar", "chain"])
def test_the_gradient_of_the_potential_is_the_residual(document):
    mech = compile_mechanism(load_document(document()))
    form = mech.graphs.energy_form
    n, m = len(form.unknowns), form.n_multipliers
    assert n + m == mech.n_free
    p = mech.p()
    x = ca.SX.sym("x", n)
    stationarity = ca.Function(
        "stationarity",
        [x],
        [ca.gradient(form.potential(x, p), x), ca.jacobian(form.equalities(x, p), x), form.equalities(x, p)],
    )
    rng = np.random.default_rng(11)
    for _ in range(3):  # deformed states that are no equilibria, with arbitrary multipliers
        x0, lam = rng.normal(scale=0.1, size=n), rng.normal(scale=2.0, size=m)
        gradient, J, g = (np.asarray(a) for a in stationarity(x0))
        R = np.asarray(mech.graphs.residual(np.concatenate([x0, lam]), p)).ravel()
        expected = np.concatenate([gradient.ravel() + J.T @ lam, g.ravel()])
        assert np.abs(R).max() > 1e-2  # far from equilibrium
        np.testing.assert_allclose(R, expected, rtol=0, atol=1e-10 * np.abs(R).max())


@pytest.mark.parametrize("document", [four_bar, chain], ids=["four_bar", "chain"])
def test_the_minimum_of_the_potential_is_the_newton_equilibrium(document):
    mech = compile_mechanism(load_document(document()))
    newton = solve_equilibrium(mech, TIGHT)
    minimum = minimize_energy(mech)
    assert newton.converged and minimum.converged
    assert np.abs(minimum.z - newton.z).max() <= 1e-8 * max(1.0, np.abs(newton.z).max())
    assert minimum.solver_residual < 1e-8


@pytest.mark.parametrize(
    "example, element, family", [("gripper.json", "a", "curved_beam"), ("cantilever.json", "beam", "link")]
)
def test_elements_without_an_energy_form_are_refused_by_name(example, element, family):
    mech = compile_mechanism(load_document(EXAMPLES / example))
    with pytest.raises(MechanismError) as info:
        minimize_energy(mech)
    assert info.value.pointer == f"/elements/{element}"
    assert info.value.problem.startswith(f"element '{element}' ({family}) has no energy form: ")
