"""The inverse analysis of link networks (seed 002 Sec. 5.3) by round trip with the forward
model: forward(eta, F) gives psi; inverse(psi, internal forces) must give eta and F back."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexmech import models
from flexmech.models import MechanismError
from flexmech.service.solvers.equilibrium import NewtonOptions, solve_equilibrium
from flexmech.service.solvers.inverse_links import inverse_links, link_states

TIGHT = NewtonOptions(tol_residual=1e-13, tol_step=1e-12)
SI = {"length": "m", "force": "N", "stress": "Pa", "angle": "rad"}
COEFFICIENTS = [0.3, -0.1]
L1, L2, ANGLE2 = 0.5, 0.4, -1.2
LOAD = (40.0, -60.0)
CHEBYSHEV_SAMPLES = 40


def eta1(u):
    return 0.2 + sum(c * np.sin(2 * (i + 1) * np.pi * u) for i, c in enumerate(COEFFICIENTS))


@pytest.fixture(scope="module")
def forward():
    """An arch: a curved link from ground A to a clamped floating joint J, a straight one on
    to ground B; a force at J. Forward-solved once."""
    u = np.linspace(0, 1, 200001)
    joint = [L1 * np.trapezoid(np.cos(eta1(u)), u), L1 * np.trapezoid(np.sin(eta1(u)), u)]
    document = {
        "name": "arch",
        "units": SI,
        "materials": {"m": {"E": 2e11}},
        "sections": {"s": {"b": 0.01, "h": 0.002}},
        "bodies": {
            "A": {"fixed": True, "position": [0, 0]},
            "J": {"joint": True, "position": joint},
            "B": {"fixed": True, "position": [joint[0] + L2 * math.cos(ANGLE2), joint[1] + L2 * math.sin(ANGLE2)]},
        },
        "elements": {
            "L1": {
                "type": "link",
                "from": "A",
                "to": "J",
                "length": L1,
                "material": "m",
                "section": "s",
                "shape": {"type": "fourier_sine", "angle": 0.2, "coefficients": COEFFICIENTS},
                "intervals": 16,
            },
            "L2": {
                "type": "link",
                "from": "J",
                "to": "B",
                "length": L2,
                "material": "m",
                "section": "s",
                "shape": {"type": "straight", "angle": ANGLE2},
            },
        },
        "loads": {"F": {"type": "force", "body": "J", "force": list(LOAD)}},
    }
    mech = models.compile_mechanism(models.load_document(document))
    result = solve_equilibrium(mech, TIGHT)
    assert result.converged
    return mech, result


def measured_shapes(mech, result) -> dict:
    """psi of every link at Chebyshev-Lobatto points (the forward model's dense output)."""
    u = 0.5 - 0.5 * np.cos(np.pi * np.arange(CHEBYSHEV_SAMPLES) / (CHEBYSHEV_SAMPLES - 1))
    return {
        name: {"samples": link_states(mech, result.z, name, u)["psi"].tolist(), "u": u.tolist()}
        for name in ("L1", "L2")
    }


def test_inverse_returns_the_initial_shapes_and_the_load(forward):
    mech, result = forward
    out = result.outputs()
    assert out["elements.L1.discretization_error"] < 1e-9
    assert abs(out["bodies.J.angle"]) > 1e-3 and abs(out["elements.L2.M_start"]) > 0.1  # bent, not just stretched
    inverse = inverse_links(
        mech,
        measured_shapes(mech, result),
        {"L1": {"h": out["elements.L1.h"], "v": out["elements.L1.v"]}},
        ["/loads/F/force/0", "/loads/F/force/1"],
        TIGHT,
    )
    assert inverse.converged, inverse.message
    assert inverse.loads["/loads/F/force/0"] == pytest.approx(LOAD[0], rel=1e-8)
    assert inverse.loads["/loads/F/force/1"] == pytest.approx(LOAD[1], rel=1e-8)
    eta = np.array(inverse.links["L1"]["eta"])
    assert np.abs(eta - eta1(np.array(inverse.links["L1"]["u"]))).max() < 1e-8
    assert np.abs(np.array(inverse.links["L2"]["eta"]) - ANGLE2).max() < 1e-8
    # The other link's internal force and the joint's rotation come back too.
    assert inverse.links["L2"]["v"] == pytest.approx(out["elements.L2.v"], rel=1e-8)
    assert inverse.bodies["J"]["rotation"] == pytest.approx(out["bodies.J.angle"], rel=1e-7)
    # And the undeformed joint is where the document put it.
    assert inverse.bodies["J"]["x0"] == pytest.approx(mech.value("/bodies/J/position/0"), abs=1e-10)


def test_inverse_from_a_polynomial_psi():
    """A polynomial psi is taken exactly: the inverse of a single clamped link with its tip
    force known gives eta = psi - (L / EI) int m du, here in closed form."""
    EI, L, F = 0.08, 0.1016, 2.0
    c = [0.0, 0.5, -0.2]
    document = {
        "name": "tip",
        "units": SI,
        "materials": {"m": {"E": EI / 1e-9}},
        "sections": {"s": {"shape": "general", "I": 1e-9}},
        "bodies": {"A": {"fixed": True, "position": [0, 0]}, "T": {"joint": True, "position": [L, 0]}},
        "elements": {
            "beam": {
                "type": "link",
                "from": "A",
                "to": "T",
                "length": L,
                "material": "m",
                "section": "s",
                "end": "pinned",
            }
        },
        "loads": {"F": {"type": "force", "body": "T", "force": [0.0, F]}},
    }
    mech = models.compile_mechanism(models.load_document(document))
    inverse = inverse_links(mech, {"beam": {"polynomial": c}}, {"beam": {"v": F}}, ["/loads/F/force/1"], TIGHT)
    assert inverse.converged, inverse.message
    assert inverse.loads["/loads/F/force/1"] == pytest.approx(F, rel=1e-12)
    assert inverse.links["beam"]["h"] == pytest.approx(0.0, abs=1e-12)
    # m(u) = F L int_u^1 cos psi: eta'(u) = psi'(u) - L m / EI; check eta at the nodes by quadrature.
    u = np.linspace(0, 1, 200001)
    psi = np.polynomial.polynomial.polyval(u, c)
    cos_psi = np.cos(psi)
    tail = np.concatenate([np.cumsum(((cos_psi[1:] + cos_psi[:-1]) / 2 * np.diff(u))[::-1])[::-1], [0.0]])
    m = F * L * tail
    integral = np.concatenate([[0.0], np.cumsum((m[1:] + m[:-1]) / 2 * np.diff(u))])
    eta = psi - L / EI * integral  # eta(0) = psi(0): clamped to ground
    nodes = np.array(inverse.links["beam"]["u"])
    assert np.abs(np.array(inverse.links["beam"]["eta"]) - np.interp(nodes, u, eta)).max() < 1e-8


@pytest.mark.parametrize(
    "shapes, forces, unknown, pointer, message",
    [
        (
            "measured",
            {"L1": {"h": 1.0}},
            ["/loads/F/force/0", "/loads/F/force/1"],
            "/internal_forces",
            "inconsistent inverse data: 1 internal force component(s) given for 2 unknown load component(s); "
            "they must be equal (Lan 2005 Sec. 5.3.2)",
        ),
        (
            {"L1": {"polynomial": [0.1]}},
            {"L1": {"h": 1.0}},
            ["/loads/F/force/0"],
            "/shapes/L2",
            "inconsistent inverse data: the deformed shape of every link is needed",
        ),
        (
            {"L1": {"polynomial": [0.1]}, "L2": {"samples": [0.1, 0.2], "u": [0.0, 0.5, 1.0]}},
            {"L1": {"h": 1.0}},
            ["/loads/F/force/0"],
            "/shapes/L2/u",
            "inconsistent inverse data: 3 positions for 2 samples",
        ),
        (
            {"L1": {"polynomial": [0.1]}, "L2": {"samples": [0.1, 0.2], "u": [0.0, 1.5]}},
            {"L1": {"h": 1.0}},
            ["/loads/F/force/0"],
            "/shapes/L2/u",
            "inconsistent inverse data: positions must be distinct and lie in [0, 1]",
        ),
        (
            "measured",
            {"L9": {"h": 1.0}},
            ["/loads/F/force/0"],
            "/internal_forces/L9",
            "no link named 'L9' (links: L1, L2)",
        ),
        (
            "measured",
            {"L1": {"h": 1.0}},
            ["/bodies/J/position/0"],
            "/unknown_loads/0",
            "'/bodies/J/position/0' is not a force or moment component of a load",
        ),
    ],
)
def test_inconsistent_inverse_data_is_named(forward, shapes, forces, unknown, pointer, message):
    mech, result = forward
    if shapes == "measured":
        shapes = measured_shapes(mech, result)
    with pytest.raises(MechanismError) as info:
        inverse_links(mech, shapes, forces, unknown)
    assert info.value.pointer == pointer
    assert info.value.problem == message
