"""Planar kinematics helpers on CasADi SX expressions."""

from __future__ import annotations

import casadi as ca

# 1~ of the paper (Eq. 14): rotates a vector by +90 degrees.
J = ca.DM([[0.0, -1.0], [1.0, 0.0]])


def rot(angle) -> ca.SX:
    """2x2 rotation matrix by `angle` (radians), counter-clockwise."""
    c, s = ca.cos(angle), ca.sin(angle)
    return ca.vertcat(ca.horzcat(c, -s), ca.horzcat(s, c))


def unit(angle) -> ca.SX:
    return ca.vertcat(ca.cos(angle), ca.sin(angle))


def cross(a, b):
    """z-component of the planar cross product a x b."""
    return a[0] * b[1] - a[1] * b[0]
