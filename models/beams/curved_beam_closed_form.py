"""Circular-arc flexure of seed 000 (Cammarata et al. 2022): closed-form compliance, frames
and the balance of the beam in its undeformed (linear) or deformed (partial non-linear) state.

Frames (all in the undeformed configuration): S_if sits at the start attachment with x along
the counter-clockwise tangent and y towards the arc centre; S_fj is S_if rotated by the arc
angle theta_f and sits at the end attachment. Eq. 2 is the compliance of the end section in
S_fj with the start section clamped.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from flexmech.models.graph.planar import J, rot, unit


def compliance(radius, arc_angle, EI) -> ca.SX:
    """C_f of Eq. 2: 3x3, maps the end wrench [Fx, Fy, M] (S_fj) to [ux, uy, phi]."""
    r, t = radius, arc_angle
    c, s = ca.cos(t), ca.sin(t)
    cxx = r**3 / 4 * (6 * t + ca.sin(2 * t) - 8 * s)
    cxy = r**3 / 2 * (c**2 - 2 * c + 1)
    cxm = r**2 * (t - s)
    cyy = r**3 / 4 * (2 * t - ca.sin(2 * t))
    cym = r**2 * (1 - c)
    cmm = r * t
    C = ca.vertcat(
        ca.horzcat(cxx, cxy, cxm),
        ca.horzcat(cxy, cyy, cym),
        ca.horzcat(cxm, cym, cmm),
    )
    return C / EI


def stiffness(radius, arc_angle, EI) -> ca.SX:
    """K_f = C_f^-1 (symbolic 3x3 inverse, exact)."""
    return ca.inv(compliance(radius, arc_angle, EI))


def chord_in_start_frame(radius, arc_angle) -> ca.SX:
    """d_f of Eq. 16: from the start to the end attachment, in S_if."""
    return ca.vertcat(radius * ca.sin(arc_angle), radius * (1 - ca.cos(arc_angle)))


def transfer_matrix(radius, arc_angle, tip_displacement=None) -> ca.SX:
    """T_f (Eq. 15) or, given the tip displacement in S_fj, T'_f (Eq. 17).

    Maps the wrench applied to the beam's end (in S_fj) to the wrench the start body applies
    to the beam (in S_if). The bottom-right entry is 1 (Eq. 33 misprints it as 0).
    """
    A_f = rot(arc_angle)
    arm = A_f.T @ chord_in_start_frame(radius, arc_angle)
    if tip_displacement is not None:
        arm = arm + tip_displacement
    top = ca.horzcat(A_f, ca.DM.zeros(2, 1))
    bottom = ca.horzcat(-(arm.T @ J), ca.DM.ones(1, 1))
    return -ca.vertcat(top, bottom)


@dataclass(frozen=True)
class ArcGeometry:
    """Undeformed geometry of an arc that runs counter-clockwise from start to end."""

    start_point: ca.SX
    end_point: ca.SX
    start_frame_angle: ca.SX  # global angle of S_if
    end_frame_angle: ca.SX  # global angle of S_fj


def arc_geometry(center, radius, start_angle, arc_angle) -> ArcGeometry:
    start_point = center + radius * unit(start_angle)
    end_point = center + radius * unit(start_angle + arc_angle)
    beta_start = start_angle + ca.pi / 2
    return ArcGeometry(start_point, end_point, beta_start, beta_start + arc_angle)


def internal_moment(radius, swept_angle, tip_wrench):
    """Bending moment in the beam at `swept_angle` back from the end section, for the end
    wrench [Fx, Fy, M] in S_fj (linear balance of the segment between there and the end)."""
    Fx, Fy, M = tip_wrench[0], tip_wrench[1], tip_wrench[2]
    return M + radius * ca.sin(swept_angle) * Fy + radius * (1 - ca.cos(swept_angle)) * Fx
