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
Frisch-Fay's solution ("Flexible Bars", 1962; SciPy's elliptic functions take m = p^2):

    k L     = K(p) - F(phi1|p)                      (fixes psi0),
    x_tip   = sqrt(2 sin psi0) / k                  (exact integral of cos(theta) ds),
    y_tip   = L - 2 [E(p) - E(phi1|p)] / k          (integral of sin(theta) ds).

Both differences cancel badly for small loads (y_tip loses ~ eps (EI / F L^2)^1.5
relative), so `cantilever_tip` evaluates an equivalent form. By the addition theorem
K - F(phi1|m) = F(chi|m) with tan(chi) = sqrt(sin psi0 / (1 - m)), and mapping phi to chi
turns sin(theta) ds into (sin psi0 - m sin^2 chi) d(chi) / (k Delta^3), Delta^2 = 1 - m sin^2 chi:

    k L   = F(chi|m)          = sin(chi) R_F(cos^2 chi, Delta^2, 1),
    y_tip = L sin psi0 - 2 m (1 - m) J / k,
    J     = int_0^chi sin^2 / Delta^3 = sin^3(chi) R_D(cos^2 chi, 1, Delta^2) / 3,

with Carlson's R_F, R_D (scipy.special.elliprf, elliprd) and every argument formed without
cancellation. Agrees with the Legendre form above to rounding where that one is accurate.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import cumulative_trapezoid, solve_bvp
from scipy.optimize import brentq
from scipy.special import elliprd, elliprf

_EPS = np.finfo(float).eps


def _chi_terms(psi0: float) -> tuple[float, float, float, float, float]:
    """For tip rotation psi0: (sin psi0, 1 - m, sin chi, cos^2 chi, Delta^2), all accurate."""
    S = math.sin(psi0)
    m1 = math.sin(math.pi / 4 - psi0 / 2) ** 2  # 1 - m = (1 - sin psi0) / 2
    d = m1 + S  # sin^2 chi = S / d, cos^2 chi = m1 / d
    return S, m1, math.sqrt(S / d), m1 / d, m1 * (1 + S) / d


def cantilever_tip(EI: float, L: float, F: float) -> tuple[float, float, float]:
    """Exact tip pose of the elastica cantilever under a dead tip force (Frisch-Fay).

    Clamped at the origin, initially along +x; the force F > 0 [N] acts at the tip in +y
    and keeps its direction. EI [N m^2], L [m]. Returns (x_tip, y_tip, tip_rotation):
    the tip coordinate along the undeformed axis [m] (-> L as F -> 0), the transverse
    deflection [m] (-> F L^3 / (3 EI)) and the tip slope angle [rad], counter-clockwise
    positive (-> F L^2 / (2 EI)). Accurate to a few ulp-level relative errors (scaled by
    the conditioning of the root) for F L^2 / EI up to about 800 (tip rotation within
    1e-12 rad of pi/2); larger loads raise ValueError.
    """
    if not (EI > 0 and L > 0 and F > 0):
        raise ValueError("need EI > 0, L > 0 and F > 0")
    k = math.sqrt(F / EI)

    def residual(psi0: float) -> float:  # F(chi|m) - k L, increasing in psi0
        _, _, s, c2, D2 = _chi_terms(psi0)
        return s * float(elliprf(c2, D2, 1.0)) - k * L

    upper = math.pi / 2 - 1e-12  # residual(0) = -k L < 0, residual -> +inf at pi/2
    if residual(upper) <= 0:
        raise ValueError("load too large for this bracket (F L^2 / EI above ~800)")
    psi0 = brentq(residual, 0.0, upper, xtol=1e-300, rtol=4 * _EPS, maxiter=500)

    S, m1, s, c2, D2 = _chi_terms(psi0)
    J = s**3 * float(elliprd(c2, 1.0, D2)) / 3
    x_tip = math.sqrt(2 * S) / k
    y_tip = L * S - 2 * (1 - m1) * m1 * J / k
    return x_tip, y_tip, psi0


def cantilever_tip_bvp(EI: float, L: float, F: float, tol: float = 1e-10) -> tuple[float, float, float]:
    """Same quantities as `cantilever_tip`, by scipy.integrate.solve_bvp (cross-check only).

    Solves theta'' = -(F L^2 / EI) cos(theta) in u = s / L with theta(0) = 0, theta'(1) = 0,
    carrying x' = cos(theta), y' = sin(theta) (x(0) = y(0) = 0) as extra states, so the tip
    follows without a separate quadrature. Returns (x_tip, y_tip, tip_rotation) in m, m, rad.

    tol is solve_bvp's bound on the relative collocation residual, not on the tip values:
    1e-10 already gives tip values good to ~1e-13, while tol near 1e-12 reaches the
    residual's rounding floor, where mesh refinement runs to max_nodes and fails.
    """
    lam = F * L**2 / EI

    def rhs(u, z):
        th = z[0]
        return np.vstack([z[1], -lam * np.cos(th), np.cos(th), np.sin(th)])

    def bc(za, zb):
        return np.array([za[0], zb[1], za[2], za[3]])

    # Guess: quadratic slope whose tip angle saturates below pi/2 (a linear guess with
    # theta(1) = lam / 2 lands on a wrong, looping branch for large loads).
    u = np.linspace(0.0, 1.0, 201)
    a = (math.pi / 2) * math.tanh(lam / math.pi)
    th = a * (2 * u - u**2)
    guess = np.vstack(
        [
            th,
            2 * a * (1 - u),
            cumulative_trapezoid(np.cos(th), u, initial=0.0),
            cumulative_trapezoid(np.sin(th), u, initial=0.0),
        ]
    )
    sol = solve_bvp(rhs, bc, u, guess, tol=tol, bc_tol=tol, max_nodes=100_000)
    if not sol.success:
        raise RuntimeError(f"solve_bvp failed: {sol.message}")
    th1, _, x1, y1 = sol.sol(1.0)
    return float(L * x1), float(L * y1), float(th1)


def timoshenko_tip_deflection(F: float, L: float, E: float, I: float, G: float, A: float, kappa: float) -> float:
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
