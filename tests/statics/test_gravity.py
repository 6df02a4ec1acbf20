"""Gravity: a link's own weight against the elastica under a distributed load (a boundary-value
oracle by scipy's solve_bvp), its mass from the section, and body weights at mass centres."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_bvp

from flexmech.models import compile_mechanism, load_document
from flexmech.service.solvers.equilibrium import NewtonOptions, solve_equilibrium

E, B, H, L, RHO, G = 200e9, 0.01, 0.001, 1.0, 7800.0, 9.81
TIGHT = NewtonOptions(tol_residual=1e-13, tol_step=1e-12, max_iterations=100)


def hanging_strip(section: dict | None = None, **link) -> dict:
    return {
        "units": {"length": "m", "force": "N", "stress": "Pa", "mass": "kg", "angle": "rad"},
        "gravity": [0, -G],
        "materials": {"steel": {"E": E, "density": RHO}},
        "sections": {"strip": section or {"b": B, "h": H}},
        "bodies": {"wall": {"fixed": True, "position": [0, 0]}, "tip": {"joint": True, "position": [L, 0]}},
        "elements": {
            "strip": {
                "type": "link",
                "from": "wall",
                "to": "tip",
                "length": L,
                "material": "steel",
                "section": "strip",
                **link,
            }
        },
        "outputs": {"wall": {"type": "reaction", "body": "wall"}},
    }


def self_weight_tip(w: float, EI: float) -> tuple[float, float]:
    """The tip of a horizontal cantilever sagging under its weight w per length: with theta
    the tangent angle, EI theta'' = w (L - s) cos(theta), theta(0) = 0, theta'(L) = 0."""

    def rhs(s, y):
        theta, kappa, _, _ = y
        return np.vstack([kappa, w * (L - s) * np.cos(theta) / EI, np.cos(theta), np.sin(theta)])

    def bc(a, b):
        return np.array([a[0], a[2], a[3], b[1]])

    s = np.linspace(0, L, 201)
    solution = solve_bvp(rhs, bc, s, np.zeros((4, s.size)), tol=1e-10, max_nodes=100_000)
    assert solution.success
    return float(solution.y[2, -1]), float(solution.y[3, -1])


def test_a_strip_sags_under_its_own_weight_as_the_distributed_elastica():
    mech = compile_mechanism(load_document(hanging_strip(intervals=16)))
    # Its weight is large: the small-deflection sag w L^4 / 8 EI would be 0.57 L.
    steps = [solve_equilibrium(mech.with_values({"/gravity/1": -G * k / 4}), TIGHT) for k in (1, 2, 3)]
    result = solve_equilibrium(mech, TIGHT, guess=steps[-1].z)
    assert result.converged
    out = result.outputs()
    w, EI = RHO * B * H * G, E * B * H**3 / 12
    x, y = self_weight_tip(w, EI)
    assert y < -0.4 * L
    assert out["bodies.tip.x"] == pytest.approx(x, abs=1e-8 * L)
    assert out["bodies.tip.y"] == pytest.approx(y, abs=1e-8 * L)
    assert out["wall.Fy"] == pytest.approx(w * L, rel=1e-12)  # the wall carries all the weight
    assert out["elements.strip.mass"] == pytest.approx(RHO * B * H * L, rel=1e-12)


def test_a_tapered_strip_has_the_mass_of_its_section():
    h0, h1 = 0.002, 0.001
    mech = compile_mechanism(
        load_document(hanging_strip({"shape": "tapered_rectangle", "b": B, "h_start": h0, "h_end": h1}))
    )
    out = solve_equilibrium(mech, TIGHT).outputs()
    assert out["elements.strip.mass"] == pytest.approx(RHO * B * (h0 + h1) / 2 * L, rel=1e-12)
    assert out["wall.Fy"] == pytest.approx(RHO * B * (h0 + h1) / 2 * L * G, rel=1e-12)


def test_a_link_with_mass_needs_its_area_and_has_no_mass_matrix():
    from flexmech.models import MechanismError
    from flexmech.service.solvers.inertia import mass_matrix

    document = hanging_strip({"shape": "general", "I": B * H**3 / 12})
    with pytest.raises(MechanismError) as info:
        compile_mechanism(load_document(document))
    assert info.value.pointer == "/sections/strip/A"
    assert info.value.problem == "the area is required: link 'strip' has mass (material 'steel' has a density)"
    with pytest.raises(MechanismError) as info:
        mass_matrix(compile_mechanism(load_document(hanging_strip())))
    assert info.value.pointer == "/elements/strip"
    assert info.value.problem.startswith("element 'strip' (link) has no mass form: it has mass")
