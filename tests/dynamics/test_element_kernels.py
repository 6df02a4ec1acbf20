"""The element kernels against independent references: an element's structured Jacobian
against CasADi's differentiation of its residual; a time step solved on the kernels against
the dense step equations of models.graph.dynamics (Lagrange's equations of the whole structure);
Newton on the kernels (chain elimination, global part) converging quadratically, which it
does only if the factored system is the residual's exact Jacobian."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from conftest import EXAMPLES

from flexmech.models import compile_mechanism, load_document
from flexmech.models.kernels.chain_signature import ChainSignature
from flexmech.models.kernels.link_chain import jacobian_function, residual_function
from flexmech.service.dynamics.engine import Engine
from flexmech.service.dynamics.histories import read_histories
from flexmech.service.dynamics.kernel_system import NEWTON_TOLERANCE
from flexmech.service.dynamics.modes import form_of
from flexmech.service.dynamics.run import scheme_of, simulation_spec, start_shape
from flexmech.service.dynamics.stepping import start_of


@pytest.mark.parametrize(
    "signature",
    [
        ChainSignature(3, True, True),
        ChainSignature(2, True, False),
        ChainSignature(1, False, False),
        ChainSignature(3, True, True, "partial"),
    ],
    ids=lambda s: s.key,
)
def test_the_element_jacobian_is_the_derivative_of_its_residual(signature):
    residual, jacobian = residual_function(signature), jacobian_function(signature)
    u = ca.SX.sym("u", signature.n_local)
    rest = [ca.SX.sym(residual.name_in(i), residual.sparsity_in(i)) for i in range(1, residual.n_in())]
    differentiated = ca.Function("ad", [u, *rest], [ca.jacobian(residual(u, *rest)[0], u)])
    rng = np.random.default_rng(7)
    data = np.abs(rng.standard_normal(signature.n_data)) + 0.5  # lengths, moduli, densities: positive
    for _ in range(3):
        args = [
            rng.standard_normal(signature.n_local),
            rng.standard_normal(3 * signature.n_c),
            np.r_[rng.uniform(0.1, 1.0, 3), 0.3],
            0.2,
            rng.standard_normal(2),
            data,
        ]
        rows, J = jacobian(*args)
        np.testing.assert_allclose(np.asarray(rows), np.asarray(residual(*args)[0]), rtol=1e-13, atol=1e-13)
        exact = np.asarray(differentiated(*args))
        np.testing.assert_allclose(np.asarray(J), exact, rtol=1e-10, atol=1e-10 * np.abs(exact).max())


def _setup(example: str, until: float = 0.1):
    mech = compile_mechanism(load_document(EXAMPLES / example))
    spec = simulation_spec(mech, {"until": until})
    histories = read_histories(mech, spec.histories, spec.until, "/simulate/histories")
    scheme = scheme_of(spec)
    x0, _ = start_shape(mech, spec)
    return mech, spec, histories, scheme, x0


def _dense_step_residual(mech, histories, scheme, state, h, t1, damping):
    """The step equations of the dense form at the unknowns u = [qdd1; lam1] (a Function of u)."""
    form = form_of(mech.structure, histories.moving)
    n = len(form.unknowns)
    x, v, a, qdd = (state[i * n : (i + 1) * n] for i in range(4))
    p1, pdot1, pddot1 = histories.at(mech.p(), t1)
    u = ca.SX.sym("u", n + form.n_equalities)
    s = scheme
    a1 = ((1 - s.alpha_f) * u[:n] + s.alpha_f * qdd - s.alpha_m * a) / (1 - s.alpha_m)
    x1 = x + h * v + h**2 * ((0.5 - s.beta) * a + s.beta * a1)
    v1 = v + h * ((1 - s.gamma) * a + s.gamma * a1)
    F = ca.vertcat(form.equations(x1, v1, u[:n], u[n:], p1, pdot1, pddot1, damping), form.constraints(x1, p1))
    return ca.Function("dense_step", [u], [F, ca.jacobian(F, u)]), n


@pytest.mark.parametrize("example", ["rod_free_vibration.json", "four_bar_dynamics.json"])
def test_a_step_on_the_kernels_solves_the_dense_step_equations(example):
    """From a state with velocities (the start, then random rates), one step by Newton on the
    kernels and one by dense Newton on models.graph.dynamics' equations agree."""
    mech, spec, histories, scheme, x0 = _setup(example)
    rng = np.random.default_rng(11)
    n = len(x0)
    v0 = 0.05 * rng.standard_normal(n)
    form = form_of(mech.structure, histories.moving)
    G = np.asarray(form.constraint_jacobian(x0, mech.p()), dtype=float).reshape(form.n_equalities, n)
    v0 -= np.linalg.pinv(G) @ (G @ v0)  # rates that keep the constraints
    start = start_of(mech.structure, mech.p(), x0, v0, histories, 0.0, scheme)
    engine = Engine(mech.structure, scheme, histories.moving)
    h = 1e-3
    p1, pdot1, pddot1 = histories.at(mech.p(), h)
    mask = histories.load_mask(len(mech.p()))
    state, _, norm = (
        np.asarray(q, dtype=float).ravel()
        for q in engine.rescue(start.state, h, p1, pdot1, pddot1, 0.0, mask, *engine.data(p1))
    )
    assert norm[0] < NEWTON_TOLERANCE
    dense, n = _dense_step_residual(mech, histories, scheme, start.state, h, h, 0.0)
    u = np.concatenate([start.state[3 * n : 4 * n], start.state[4 * n :]])
    for _ in range(20):
        F, J = (np.asarray(q, dtype=float) for q in dense(u))
        u = u - np.linalg.solve(J, F.ravel())
    kernel_u = np.concatenate([state[3 * n : 4 * n], state[4 * n :]])
    scale = np.abs(u).max()
    np.testing.assert_allclose(kernel_u, u, rtol=0, atol=1e-8 * scale)


def test_newton_on_the_kernels_converges_quadratically():
    """Full Newton steps on the four-bar's kernel system, a long step (0.1 s: the stiffness
    outweighs the mass) from a poor guess: the residual squares near the solution, the sign
    of an exact Jacobian (a wrong block would leave linear convergence)."""
    mech, spec, histories, scheme, x0 = _setup("four_bar_dynamics.json")
    start = start_of(mech.structure, mech.p(), x0, np.zeros(len(x0)), histories, 0.0, scheme)
    engine = Engine(mech.structure, scheme, histories.moving)
    st, system = engine.stepper, engine.system
    state, h, p, pdot, pddot, damping, mask, data = st._symbols()
    _, k = st.coefficients(h)
    affine, _ = st._affine(state, h)
    si = system.step_inputs(affine, k, p, pdot, pddot, damping, mask, data)
    Z = ca.MX.sym("Z", system.n_z)
    factors = system.factorize(Z, si)
    one = ca.MX(1)
    ev = system.evaluate(Z, one, si, factors.kept_reverse)
    newton = ca.Function(
        "newton", [Z, state, h, p, pdot, pddot, damping, mask, *data], [Z - system.solve(ev, one, factors), ev.norm]
    )
    p1, pdot1, pddot1 = histories.at(mech.p(), 0.1)
    args = [start.state, 0.1, p1, pdot1, pddot1, 0.0, histories.load_mask(len(p1)), *engine.data(p1)]
    z = np.random.default_rng(5).standard_normal(system.n_z)  # far from the step: every row of order 1
    norms = []
    for _ in range(8):
        z_next, norm = newton(z, *args)
        norms.append(float(norm))
        z = np.asarray(z_next, dtype=float).ravel()
    converged = next(i for i, norm in enumerate(norms) if norm < NEWTON_TOLERANCE)
    assert norms[0] > 1.0 and converged <= 6, norms
    a, b = norms[converged - 2], norms[converged - 1]  # the last two before round-off
    assert a < 1e-2 and np.log(b) / np.log(a) > 1.8, norms  # |F+| ~ C |F|^2: the exponent is 2


@pytest.mark.parametrize("example", ["rod_free_vibration.json", "four_bar_dynamics.json"])
def test_the_expanded_window_steps_as_the_window_of_calls_does(example):
    """Interpreted kernels run each Newton iteration as one expanded SX Function gated as a
    whole (service.dynamics.kernel_window): the same operations as the window of MX calls, so
    the same states, monitors, residuals and iteration counts, to round-off; a gate that let a
    converged iteration run, or kept the wrong part of the carry, would show here."""
    mech, spec, histories, scheme, x0 = _setup(example)
    start = start_of(mech.structure, mech.p(), x0, np.zeros(len(x0)), histories, 0.0, scheme)
    h, steps = spec.step, 20
    P, PD, PDD = histories.at_times(mech.p(), h * np.arange(1, steps + 1))
    mask = histories.load_mask(len(mech.p()))
    windows = {}
    for expanded in (True, False):
        engine = Engine(mech.structure, scheme, histories.moving)
        assert engine.stepper.expanded  # no compiled kernels: they run interpreted, expanded
        engine.stepper.expanded = expanded
        window = engine.glue_window(steps)
        windows[expanded] = [
            np.asarray(q, dtype=float)
            for q in window(start.state, h, P, PD, PDD, 0.0, mask, steps, *engine.data(P[:, 0]))
        ]
    S, monitors, norms, iterations = windows[True]
    assert np.all(norms <= 10 * NEWTON_TOLERANCE) and iterations.sum() >= 2 * steps, (norms, iterations)
    np.testing.assert_array_equal(iterations, windows[False][3])
    for ours, theirs in zip(windows[True][:2], windows[False][:2]):
        np.testing.assert_allclose(ours, theirs, rtol=1e-12, atol=1e-12 * np.abs(theirs).max())
