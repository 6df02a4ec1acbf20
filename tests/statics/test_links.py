"""Distributed elastica links (seed 002) against exact solutions.

Every test builds a small link document, solves it with the same Newton as every other
mechanism, and compares with a closed form: Frisch-Fay's elliptic-integral cantilever, the
circular arc of a pure end moment, Euler-Bernoulli and Timoshenko small-deflection formulas,
the curved-beam compliance of seed 000 Eq. 2, and the axial stretch F L / EA.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from elastica_oracles import cantilever_tip, circular_arc_tip, timoshenko_tip_deflection

from flexmech import models
from flexmech.models.beams import curved_beam_closed_form as curved_beam
from flexmech.service.solvers.equilibrium import NewtonOptions, solve_equilibrium

# The thesis cantilever (Sec. 2.5.1): EI = 0.08 N m^2, L = 101.6 mm, F = 15 N.
EI, L, F = 0.08, 0.1016, 15.0
TIGHT = NewtonOptions(tol_residual=1e-13, tol_step=1e-12)


def link_document(*, load=None, moment=None, shape=None, section=None, material=None, **link) -> dict:
    """A link clamped at the origin (ground), its u = 1 end on the body `tip`."""
    element = {"type": "link", "from": "ground", "to": "tip", "length": L, "material": "m", "section": "s"}
    element.update(link)
    if shape is not None:
        element["shape"] = shape
    loads = {}
    if load is not None:
        loads["F"] = {"type": "force", "body": "tip", "force": list(load)}
    if moment is not None:
        loads["M"] = {"type": "moment", "body": "tip", "moment": moment}
    return {
        "name": "link test",
        "units": {"length": "m", "force": "N", "stress": "Pa", "angle": "rad"},
        "materials": {"m": material or {"E": EI / 1e-9}},
        "sections": {"s": section or {"shape": "general", "I": 1e-9}},
        "bodies": {"ground": {"fixed": True, "position": [0, 0]}, "tip": {"position": [L, 0]}},
        "elements": {"beam": element},
        "loads": loads,
    }


def solve(document: dict, options: NewtonOptions = TIGHT):
    mech = models.compile_mechanism(models.load_document(document))
    result = solve_equilibrium(mech, options)
    assert result.converged, result.message
    return mech, result, result.outputs()


def linear_response(mech, pointer: str) -> np.ndarray:
    """dz/d(load) at the undeformed state: the exact small-load limit, K_T^-1 dR/dload."""
    p0 = mech.p()
    p1 = mech.with_values({pointer: 1.0}).p()
    p0[mech.parameter_index(pointer)] = 0.0
    zero = np.zeros(mech.n_free)
    R0, K = mech.graphs.residual_and_tangent(zero, p0)
    R1 = mech.graphs.residual(zero, p1)
    return -np.linalg.solve(np.asarray(K), np.asarray(R1 - R0).ravel()), p0


def tip_of(mech, z, p) -> np.ndarray:
    """(x_end, y_end, rotation_end) of the link, in document units."""
    y = np.asarray(mech.graphs.outputs(z, p)).ravel()
    names = mech.graphs.output_names
    values = [y[names.index(f"elements.beam.{q}")] for q in ("x_end", "y_end", "rotation_end")]
    return np.array([values[0] / mech.nd_per_doc("length"), values[1] / mech.nd_per_doc("length"), values[2]])


def test_cantilever_matches_the_elliptic_integral_solution():
    _, result, out = solve(link_document(load=(0, F)))
    x, y, rotation = cantilever_tip(EI, L, F)
    assert out["elements.beam.x_end"] == pytest.approx(x, rel=1e-9)
    assert out["elements.beam.y_end"] == pytest.approx(y, rel=1e-9)
    assert out["elements.beam.rotation_end"] == pytest.approx(rotation, rel=1e-9)
    assert out["bodies.tip.angle"] == pytest.approx(rotation, rel=1e-9)
    # The internal force is the tip load; the root moment balances it about the clamp.
    assert out["elements.beam.v"] == pytest.approx(F, rel=1e-12)
    assert out["elements.beam.M_start"] == pytest.approx(F * x, rel=1e-9)
    assert result.iterations <= 8


@pytest.mark.parametrize("order, intervals", [(4, (2, 4, 8)), (6, (2, 4, 8)), (8, (1, 2, 4))])
def test_discretization_error_falls_at_the_integrators_order(order, intervals):
    x, y, _ = cantilever_tip(EI, L, F)
    errors, estimates = [], []
    for K in intervals:
        _, _, out = solve(link_document(load=(0, F), intervals=K, order=order))
        errors.append(abs(out["elements.beam.y_end"] - y) / y)
        estimates.append(out["elements.beam.discretization_error"])
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert rates.mean() == pytest.approx(order, abs=0.6), rates
    # The reported accuracy is an estimate of the same error (within a small factor).
    for error, estimate in zip(errors, estimates):
        assert error / 3 < estimate < 5 * error


def test_end_moment_bends_a_straight_link_into_a_circular_arc():
    M = 0.9  # N m: curvature M / EI turns the tip by M L / EI = 1.143 rad
    _, _, out = solve(link_document(moment=M))
    x, y, rotation = circular_arc_tip(M, EI, L)
    assert out["elements.beam.x_end"] == pytest.approx(x, rel=1e-10)
    assert out["elements.beam.y_end"] == pytest.approx(y, rel=1e-10)
    assert out["elements.beam.rotation_end"] == pytest.approx(rotation, rel=1e-10)
    assert out["elements.beam.M_start"] == pytest.approx(M, rel=1e-10)
    assert out["elements.beam.energy"] == pytest.approx(M**2 * L / (2 * EI), rel=1e-10)


def test_small_loads_match_linear_euler_bernoulli():
    mech = models.compile_mechanism(models.load_document(link_document(load=(0, F))))
    dz, p0 = linear_response(mech, "/loads/F/force/1")
    eps = 1e-6  # nondimensional step along the exact tangent
    slope = (tip_of(mech, eps * dz, p0) - tip_of(mech, -eps * dz, p0)) / (2 * eps)
    per_newton = slope  # the load parameter moved by 1 N
    assert per_newton[1] == pytest.approx(L**3 / (3 * EI), rel=1e-8)
    assert per_newton[2] == pytest.approx(L**2 / (2 * EI), rel=1e-8)
    assert abs(per_newton[0]) < 1e-8 * L**3 / EI
    # And a genuinely small load lands on the same line.
    small = 1e-4
    _, _, out = solve(link_document(load=(0, small)))
    assert out["elements.beam.y_end"] == pytest.approx(small * L**3 / (3 * EI), rel=1e-6)


def test_initially_circular_link_matches_the_curved_beam_compliance_of_seed_000():
    radius, arc = 0.05, 2.0  # rad
    E, b, h = 2e11, 0.01, 0.001
    document = link_document(
        shape={"type": "arc", "angle": 0.0, "sweep": arc},
        length=radius * arc,
        section={"b": b, "h": h},
        material={"E": E},
    )
    end = [radius * math.sin(arc), radius * (1 - math.cos(arc))]
    document["bodies"]["tip"]["position"] = end
    document["loads"] = {
        "F": {"type": "force", "body": "tip", "force": [0.0, 0.0]},
        "M": {"type": "moment", "body": "tip", "moment": 0.0},
    }
    mech = models.compile_mechanism(models.load_document(document))
    C = np.array(curved_beam.compliance(radius, arc, E * b * h**3 / 12))
    A = np.array([[math.cos(arc), -math.sin(arc)], [math.sin(arc), math.cos(arc)]])  # S_fj axes
    to_length = 1 / mech.nd_per_doc("length")
    columns = []
    for pointer in ("/loads/F/force/0", "/loads/F/force/1", "/loads/M/moment"):
        dz, _ = linear_response(mech, pointer)  # per 1 N or 1 N m
        columns.append(np.concatenate([A.T @ (dz[:2] * to_length), [dz[2]]]))  # tip motion in S_fj
    # Columns answer global Fx, Fy and M; Eq. 2's columns answer a wrench given in S_fj.
    response = np.array(columns).T
    response_fj = np.column_stack([response[:, :2] @ A, response[:, 2]])
    assert np.allclose(response_fj, C, rtol=1e-6, atol=1e-6 * np.abs(C).max())
    assert np.abs(response_fj - C).max() / np.abs(C).max() < 1e-9


def test_shear_on_a_short_thick_cantilever_matches_timoshenko():
    length, b, h, E, nu = 0.02, 0.01, 0.008, 2e11, 0.3
    G = E / (2 * (1 + nu))
    I, A = b * h**3 / 12, b * h
    document = link_document(
        length=length, section={"b": b, "h": h}, material={"E": E, "nu": nu}, shear=True, load=(0, 1.0)
    )
    document["bodies"]["tip"]["position"] = [length, 0]
    mech = models.compile_mechanism(models.load_document(document))
    dz, _ = linear_response(mech, "/loads/F/force/1")
    deflection = dz[1] / mech.nd_per_doc("length")  # per 1 N
    expected = timoshenko_tip_deflection(1.0, length, E, I, G, A, 5 / 6)
    bending_only = length**3 / (3 * E * I)
    assert expected > 1.1 * bending_only  # shear matters here: the check can tell them apart
    assert deflection == pytest.approx(expected, rel=1e-9)


def test_axial_strain_stretches_a_straight_link_by_FL_over_EA():
    b, h, E = 0.01, 0.002, 7e10
    force = 2e4  # N: strain 1.4e-2, far from small, still exactly F L / EA when straight
    _, _, out = solve(link_document(section={"b": b, "h": h}, material={"E": E}, axial=True, load=(force, 0)))
    assert out["elements.beam.x_end"] - L == pytest.approx(force * L / (E * b * h), rel=1e-10)
    assert out["elements.beam.energy"] == pytest.approx(force**2 * L / (2 * E * b * h), rel=1e-10)


def test_link_tangent_stiffness_equals_finite_differences_of_the_residual():
    mech = models.compile_mechanism(
        models.load_document(
            link_document(
                load=(3.0, F),
                shape={"type": "polynomial", "coefficients": [0.1, 0.4, -0.3]},
                section={"shape": "tapered_rectangle", "b": 0.01, "h_start": 0.002, "h_end": 0.001},
                material={"E": 2e11, "nu": 0.3},
                shear=True,
                axial=True,
                intervals=3,
            )
        )
    )
    rng = np.random.default_rng(7)
    z = 1e-2 * rng.standard_normal(mech.n_free)
    p = mech.p()
    _, K = mech.graphs.residual_and_tangent(z, p)
    step = 1e-6
    columns = [
        (np.asarray(mech.graphs.residual(z + step * e, p)) - np.asarray(mech.graphs.residual(z - step * e, p))).ravel()
        / (2 * step)
        for e in np.eye(mech.n_free)
    ]
    assert np.allclose(np.asarray(K), np.array(columns).T, rtol=1e-6, atol=1e-7)


def test_condensed_tangent_stiffness_of_a_link_is_the_beam_element_stiffness():
    """Unloaded, the tip's 3x3 K_T (links' unknowns condensed out) is the Euler-Bernoulli
    beam stiffness: EA/L axially, 12EI/L^3, -6EI/L^2, 4EI/L in bending."""
    from flexmech.service.solvers.stiffness import tangent_stiffness

    A = 1e-4
    mech = models.compile_mechanism(
        models.load_document(link_document(load=(0, 0), axial=True, section={"shape": "general", "I": 1e-9, "A": A}))
    )
    kt = tangent_stiffness(mech)
    E = EI / 1e-9
    expected = np.array([[E * A / L, 0, 0], [0, 12 * EI / L**3, -6 * EI / L**2], [0, -6 * EI / L**2, 4 * EI / L]])
    assert kt.coordinates == ["tip.x", "tip.y", "tip.angle"]
    assert np.allclose(kt.K, expected, rtol=1e-9, atol=1e-9 * np.abs(expected).max())
    assert kt.symmetric
    inextensible = models.compile_mechanism(models.load_document(link_document(load=(0, 0))))
    with pytest.raises(models.MechanismError, match="the tangent stiffness is infinite in some direction"):
        tangent_stiffness(inextensible)


def test_bounds_pick_the_buckled_branch_of_a_column():
    """A clamped column under 1.2 x Euler's load P_cr = pi^2 EI / (4 L^2): Newton from the
    straight state stays straight; bounds on the tip's sideways motion (Sec. 2.2.2) find the
    buckled elastica, whose tip rotation alpha solves k L = K(sin(alpha / 2)), k^2 = P / EI,
    with sideways deflection y* = 2 sin(alpha / 2) / k. (The bounds must put the start in
    the branch's basin: here the tip is held beyond 0.7 y*.)"""
    from scipy.optimize import brentq
    from scipy.special import ellipk

    from flexmech.service.solvers.equilibrium import solve_bounded

    P = 1.2 * math.pi**2 * EI / (4 * L**2)
    k = math.sqrt(P / EI)
    alpha = brentq(lambda a: ellipk(math.sin(a / 2) ** 2) - k * L, 1e-6, math.pi - 1e-9, xtol=1e-15)
    deflection = 2 * math.sin(alpha / 2) / k
    document = link_document(load=(-P, 0.0))
    _, straight, out = solve(document)
    assert abs(out["bodies.tip.y"]) < 1e-12
    mech = models.compile_mechanism(models.load_document(document))
    for sign in (1, -1):
        bounds = {"tip.y": (0.7 * deflection, None)} if sign > 0 else {"tip.y": (None, -0.7 * deflection)}
        result = solve_bounded(mech, bounds, TIGHT)
        assert result.converged, result.message
        buckled = result.outputs()
        assert buckled["bodies.tip.angle"] == pytest.approx(sign * alpha, rel=1e-9)
        assert buckled["bodies.tip.y"] == pytest.approx(sign * deflection, rel=1e-9)
    # Bounds that hold no equilibrium give a status and the reason, not an exception.
    beyond = solve_bounded(mech, {"tip.y": (0.9 * L, None)}, TIGHT)
    assert beyond.status == "not_converged"
    assert beyond.message.startswith("no equilibrium within the bounds: the least residual there is")
    with pytest.raises(models.MechanismError, match="/bounds/tip.y: lower bound 1 is above the upper bound 0"):
        solve_bounded(mech, {"tip.y": (1, 0)})
