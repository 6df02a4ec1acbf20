"""Closed-form (and one independent numerical) reference solutions for cantilever tests.

Common frame and units (SI throughout: N, m, N m^2, Pa, rad): the beam is clamped at the
origin and initially lies along +x with length L; y is the transverse direction; angles are
measured from +x, positive counter-clockwise. Every beam is inextensible and of uniform
bending stiffness EI unless the docstring says otherwise. This module holds helpers only.

Elastica under a dead tip force F in +y. With theta(s) the slope angle at arc length s,
the bending moment is EI theta' = F (x_tip - x), hence

    EI theta'' = -F cos(theta),   theta(0) = 0,   theta'(L) = 0.

Multiplying by theta' and integrating with zero curvature at the tip (theta = psi0 there):

    theta'^2 = 2 k^2 (sin psi0 - sin theta),   k^2 = F / EI.

Substituting 1 + sin(theta) = 2 p^2 sin^2(phi) with p^2 = (1 + sin psi0) / 2 turns
ds = d(theta) / (k sqrt(2 (sin psi0 - sin theta))) into d(phi) / (k sqrt(1 - p^2 sin^2 phi));
phi runs from phi1 (sin phi1 = 1 / (p sqrt 2), the clamp) to pi/2 (the tip). This gives

    k L     = K(p) - F(phi1|p)                      (fixes psi0),
    x_tip   = sqrt(2 sin psi0) / k                  (exact integral of cos(theta) ds),
    y_tip   = L - 2 [E(p) - E(phi1|p)] / k          (integral of sin(theta) ds),

as in Frisch-Fay, "Flexible Bars" (1962). SciPy's elliptic functions take m = p^2.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_bvp
from scipy.optimize import brentq
from scipy.special import ellipe, ellipeinc, ellipkinc, ellipkm1

_EPS = np.finfo(float).eps


def cantilever_tip(EI: float, L: float, F: float) -> tuple[float, float, float]:
    """Exact tip pose of the elastica cantilever under a dead tip force (Frisch-Fay).

    Clamped at the origin, initially along +x; the force F > 0 [N] acts at the tip in +y
    and keeps its direction. EI [N m^2], L [m]. Returns (x_tip, y_tip, tip_rotation):
    the tip coordinate along the undeformed axis [m] (-> L as F -> 0), the transverse
    deflection [m] (-> F L^3 / (3 EI)) and the tip slope angle [rad], counter-clockwise
    positive (-> F L^2 / (2 EI)).

    Valid for F L^2 / EI up to about 800 (tip rotation within 1e-12 rad of pi/2). y_tip is
    L minus a quantity close to L, so for tiny loads its relative accuracy is only about
    eps * EI / (F L^2).
    """
    if not (EI > 0 and L > 0 and F > 0):
        raise ValueError("need EI > 0, L > 0 and F > 0")
    k = math.sqrt(F / EI)

    def parts(psi0: float) -> tuple[float, float, float]:
        """Return (m, 1 - m, phi1) accurately for the tip rotation psi0."""
        s = math.sin(psi0)
        m1 = math.sin(math.pi / 4 - psi0 / 2) ** 2  # 1 - m = (1 - sin psi0) / 2
        phi1 = math.atan2(1.0, math.sqrt(s))  # sin phi1 = 1 / sqrt(1 + sin psi0)
        return (1 + s) / 2, m1, phi1

    def residual(psi0: float) -> float:
        m, m1, phi1 = parts(psi0)
        return float(ellipkm1(m1) - ellipkinc(phi1, m)) - k * L

    # residual(0) = -kL < 0; residual grows without bound as psi0 -> pi/2.
    upper = math.pi / 2 - 1e-12
    if residual(upper) <= 0:
        raise ValueError("load too large for this bracket (F L^2 / EI above ~800)")
    psi0 = brentq(residual, 0.0, upper, xtol=1e-300, rtol=4 * _EPS, maxiter=500)

    m, _, phi1 = parts(psi0)
    x_tip = math.sqrt(2 * math.sin(psi0)) / k
    y_tip = L - 2 * float(ellipe(m) - ellipeinc(phi1, m)) / k
    return x_tip, y_tip, psi0


def cantilever_tip_bvp(EI: float, L: float, F: float, tol: float = 1e-12) -> tuple[float, float, float]:
    """Same quantities as `cantilever_tip`, by scipy.integrate.solve_bvp (cross-check only).

    Solves theta'' = -(F L^2 / EI) cos(theta) in u = s / L with theta(0) = 0, theta'(1) = 0,
    carrying x' = cos(theta), y' = sin(theta) (x(0) = y(0) = 0) as extra states, so the tip
    follows without a separate quadrature. Returns (x_tip, y_tip, tip_rotation) in m, m, rad.
    """
    lam = F * L**2 / EI

    def rhs(u, z):
        th, dth = z[0], z[1]
        return np.vstack([dth, -lam * np.cos(th), np.cos(th), np.sin(th)])

    def bc(za, zb):
        return np.array([za[0], zb[1], za[2], za[3]])

    u = np.linspace(0.0, 1.0, 2001)  # a fine start mesh keeps tol = 1e-12 reachable
    th = lam * (u - u**2 / 2)  # linear (small-deflection) guess
    guess = np.vstack([th, lam * (1 - u), u, lam * (u**2 / 2 - u**3 / 6)])
    sol = solve_bvp(rhs, bc, u, guess, tol=tol, bc_tol=tol, max_nodes=100_000)
    if not sol.success:
        raise RuntimeError(f"solve_bvp failed: {sol.message}")
    th1, _, x1, y1 = sol.sol(1.0)
    return float(L * x1), float(L * y1), float(th1)


def timoshenko_tip_deflection(F: float, L: float, E: float, I: float, G: float, A: float,
                              kappa: float) -> float:
    """Small-deflection tip deflection [m] of a Timoshenko cantilever under a tip force.

    Bending plus shear: F L^3 / (3 E I) + F L / (kappa G A), with F [N], L [m], E and G [Pa],
    I [m^4], A [m^2] and kappa the (dimensionless) shear correction factor.
    """
    return F * L**3 / (3 * E * I) + F * L / (kappa * G * A)


def circular_arc_tip(M: float, EI: float, L: float) -> tuple[float, float, float]:
    """Exact tip pose of a cantilever (clamped at the origin, along +x) under an end moment.

    A pure moment M [N m] (counter-clockwise positive, M != 0) bends the inextensible beam
    into a circular arc of curvature M / EI; its centre is at (0, EI / M). Returns
    (x_tip, y_tip, rotation) = (R sin(phi), R (1 - cos(phi)), phi) with R = EI / M and
    phi = M L / EI, in m, m, rad.
    """
    phi = M * L / EI
    R = EI / M
    return R * math.sin(phi), R * (1 - math.cos(phi)), phi
