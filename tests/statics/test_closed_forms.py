"""Mechanisms other than the four-bar, against closed forms computed independently here:
the compliance of a circular arc by Castigliano's theorem (numerical quadrature of the
bending energy), and rigid-body transport of wrenches and displacements."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from flexmech.models import compile_mechanism, load_document
from flexmech.service import NewtonOptions, solve_equilibrium, tangent_stiffness

E, B, H = 200e9, 5e-3, 0.5e-3  # steel strip, SI
EI = E * B * H**3 / 12


def castigliano_compliance(r: float, theta: float) -> np.ndarray:
    """Tip compliance of a clamped circular arc (bending only) in its end frame: the moment
    at the section swept back by t from the tip is g(t) . [Fx, Fy, M] with
    g = [r (1 - cos t), r sin t, 1]; C_ij = int g_i g_j r dt / EI."""

    def g(t):
        return np.array([r * (1 - math.cos(t)), r * math.sin(t), 1.0])

    C = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            C[i, j] = quad(lambda t: g(t)[i] * g(t)[j] * r, 0, theta, epsabs=0, epsrel=1e-12, limit=200)[0] / EI
    return C


def rot(a):
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


def flexure(frm, to, center, radius, start_deg, arc_deg, model="partial_nonlinear", direction="ccw"):
    return {
        "type": "curved_beam",
        "from": frm,
        "to": to,
        "center": list(center),
        "radius": radius,
        "start_angle": start_deg,
        "arc_angle": arc_deg,
        "direction": direction,
        "material": "steel",
        "section": "strip",
        "model": model,
    }


def document(bodies, elements, loads):
    return {
        "units": {"length": "m", "force": "N", "stress": "Pa", "angle": "deg"},
        "materials": {"steel": {"E": E}},
        "sections": {"strip": {"b": B, "h": H}},
        "bodies": bodies,
        "elements": elements,
        "loads": loads,
    }


@pytest.mark.parametrize("arc_deg", [60.0, 180.0, 300.0])
def test_eq_2_equals_castigliano(arc_deg):
    from flexmech.models.beams.curved_beam_closed_form import compliance

    r, theta = 0.01, math.radians(arc_deg)
    C = np.array(compliance(r, theta, EI))
    np.testing.assert_allclose(C, castigliano_compliance(r, theta), rtol=1e-10)


@pytest.mark.parametrize("model", ["linear", "partial_nonlinear"])
@pytest.mark.parametrize("direction", ["ccw", "cw"])
def test_body_on_one_flexure_moves_by_C_f_w(model, direction):
    r, start, arc = 0.01, 30.0, 250.0
    center = np.array([0.02, 0.01])
    sign = 1 if direction == "ccw" else -1
    tip_angle = math.radians(start + sign * arc)
    tip = center + r * np.array([math.cos(tip_angle), math.sin(tip_angle)])
    doc = document(
        {"ground": {"fixed": True, "position": [0.0, 0.0]}, "stage": {"position": tip.tolist()}},
        {"f": flexure("ground", "stage", center, r, start, arc, model, direction)},
        {
            "push": {"type": "force", "body": "stage", "force": [0.0, 0.0]},
            "twist": {"type": "moment", "body": "stage", "moment": 0.0},
        },
    )
    mech = compile_mechanism(load_document(doc))
    # N, N, N m: rotations ~1e-7 rad, so geometric non-linearity stays below the tolerance
    w = np.array([3e-6, -2e-6, 1e-8])
    loaded = mech.with_values({"/loads/push/force/0": w[0], "/loads/push/force/1": w[1], "/loads/twist/moment": w[2]})
    eq = solve_equilibrium(loaded, NewtonOptions(tol_residual=1e-15, tol_step=1e-15))
    assert eq.converged
    d = eq.displacements()
    moved = np.array([d["stage.x"], d["stage.y"], math.radians(d["stage.angle"])])

    # Closed form: a ccw arc clamped at its start; for "cw" the stage end is the ccw arc's start,
    # so the stage sees the arc clamped at its end: use the compliance seen from that end.
    if direction == "ccw":
        beta = math.radians(start) + math.pi / 2 + math.radians(arc)  # end frame S_fj
        C = castigliano_compliance(r, math.radians(arc))
        T = np.eye(3)
        T[:2, :2] = rot(beta)
        expected = T @ C @ T.T @ w
    else:
        # Clamped at the ccw arc's end: by reciprocity the start-section compliance is that of
        # the mirrored arc; compute it directly by quadrature about the free (start) section.
        theta = math.radians(arc)
        s_angle = math.radians(start - arc)  # ccw start angle about the centre
        free = center + r * np.array([math.cos(s_angle), math.sin(s_angle)])

        def g(t):  # moment at arc angle s_angle + t from a unit wrench at the free start point
            pt = center + r * np.array([math.cos(s_angle + t), math.sin(s_angle + t)])
            arm = free - pt
            return np.array([-arm[1], arm[0], 1.0])  # moment = M + arm x F

        C = np.zeros((3, 3))
        for i in range(3):
            for j in range(3):
                C[i, j] = quad(lambda t: g(t)[i] * g(t)[j] * r, 0, theta, epsrel=1e-13)[0] / EI
        expected = C @ w
    np.testing.assert_allclose(moved, expected, rtol=1e-6)


def test_two_flexure_parallel_guide():
    """A stage held by two identical arcs, one above the other, joined to the ground at the
    same side: the stage stiffness is the sum of the two arcs' stiffnesses carried to the
    stage reference point, K = sum B_f^T C_f^-1 B_f with the rigid transport B_f."""
    r, start, arc, gap = 0.01, -90.0, 180.0, 0.04
    bodies = {"ground": {"fixed": True, "position": [0.0, 0.0]}, "stage": {"position": [0.0, gap / 2]}}
    elements = {
        "lower": flexure("ground", "stage", (0.0, 0.0), r, start, arc),
        "upper": flexure("ground", "stage", (0.0, gap), r, start, arc),
    }
    loads = {"push": {"type": "force", "body": "stage", "force": [0.0, 0.0]}}
    mech = compile_mechanism(load_document(document(bodies, elements, loads)))

    C_f = castigliano_compliance(r, math.radians(arc))
    K_f = np.linalg.inv(C_f)
    beta = math.radians(start + arc) + math.pi / 2
    K_closed = np.zeros((3, 3))
    for center_y in (0.0, gap):
        tip = np.array([0.0, center_y]) + r * np.array(
            [math.cos(math.radians(start + arc)), math.sin(math.radians(start + arc))]
        )
        s = tip - np.array([0.0, gap / 2])  # from the stage reference point to the attachment
        Bf = np.zeros((3, 3))
        Bf[:2, :2] = rot(beta).T
        Bf[:2, 2] = rot(beta).T @ np.array([-s[1], s[0]])
        Bf[2, 2] = 1.0
        K_closed += Bf.T @ K_f @ Bf

    ts = tangent_stiffness(mech)
    K = ts.K * np.array([1, 1, 180 / math.pi])[None, :]  # document angles are degrees
    np.testing.assert_allclose(K, K_closed, rtol=1e-9, atol=1e-9 * np.abs(K_closed).max())

    # A small horizontal push at the reference point, which lies midway, mostly translates:
    F = 1e-3
    eq = solve_equilibrium(mech.with_values({"/loads/push/force/0": F}))
    d = eq.displacements()
    expected = np.linalg.solve(K_closed, [F, 0.0, 0.0])
    moved = [d["stage.x"], d["stage.y"], math.radians(d["stage.angle"])]
    np.testing.assert_allclose(moved, expected, rtol=1e-5, atol=1e-12 * abs(expected[0]))
    assert abs(math.radians(d["stage.angle"])) * gap < 1e-3 * abs(d["stage.x"])  # parallel motion
