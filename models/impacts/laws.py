"""Normal contact laws (seed 004 Eqs. 13-25), Hertz's stiffness from geometry and materials
(Eqs. 14-17), the ESDU-78035 law of a pin in a hole (Eq. 18) solved exactly, and Ambrosio's
friction (Eq. 26). Forces are CasADi expressions of the indentation q >= 0, its rate qdot
(positive while the surfaces approach) and the rate frozen at contact onset, qdot_minus.
"""

from __future__ import annotations

import math

import casadi as ca

# Newton steps on the ESDU law in log form: from the asymptotic start, 6 reach machine
# precision for every indentation the law covers (tested against scipy's Lambert W).
ESDU_NEWTON_STEPS = 6


def damping_factor(law: str, restitution):
    """The d of F = K q^n (1 + d qdot / qdot_minus): Hunt-Crossley (21), Lankarani-Nikravesh
    (22), Flores (23); Hertz has none."""
    c = restitution
    if law == "hertz":
        return 0.0
    if law == "hunt_crossley":
        return 1.5 * (1 - c)
    if law == "flores":
        return 8 * (1 - c) / (5 * c)
    return 0.75 * (1 - c**2)  # lankarani_nikravesh and lna_esdu (Eq. 25)


def esdu_force(q, compliance_sum, length, clearance):
    """(F, dF/dq) of the ESDU law q = F (s/L) [ln(4 L dR / (F s)) + 1] (Eq. 18), s = sigma1 +
    sigma2, dR = R_hole - R_pin, solved for F exactly: with F = b e^-z (b = 4 L dR / s),
    q / (a b) = e^-z (1 + z) (a = s / L), Newton on z - ln(1 + z) + ln(q / (a b)) = 0.
    dq/dF = a z gives the tangent stiffness K_ESDU = 1 / (a z). Beyond q = a b (= 4 dR, far
    deeper than any contact) the law has no solution: the indentation is clipped there."""
    a = compliance_sum / length
    b = 4 * length * clearance / compliance_sum
    ratio = ca.fmin(ca.fmax(q / (a * b), 1e-300), 1.0)
    log_ratio = ca.log(ratio)
    z = -log_ratio + ca.log(1 - log_ratio)  # asymptotic root for small ratios
    for _ in range(ESDU_NEWTON_STEPS):
        z = ca.fmax(z - (z - ca.log1p(z) + log_ratio) * (1 + z) / ca.fmax(z, 1e-12), 0.0)
    force = b * ca.exp(-z)
    return force, 1 / (a * ca.fmax(z, 1e-12))


def normal_force(law: str, K, exponent, restitution, q, qdot, qdot_minus, esdu=None):
    """F_N >= 0 of the law at indentation q > 0 (the caller applies it only in contact). The
    LNA-ESDU law (Eq. 24) reads here F_E(q) + d K_ESDU(q) q qdot / qdot_minus: the ESDU elastic
    force with Lankarani-Nikravesh damping at the ESDU tangent stiffness (Eq. 24 as printed
    lacks the q that makes its damping term a force)."""
    d = damping_factor(law, restitution)
    q = ca.fmax(q, 0.0)
    if law == "lna_esdu":
        elastic, tangent = esdu_force(q, *esdu)
        return ca.fmax(elastic + d * tangent * q * qdot / qdot_minus, 0.0)
    # 0 at q = 0 exactly as 0^n, with derivatives that stay finite there: q^n's by n is
    # q^n ln q, 0 * -inf (a run's sensitivities differentiate the law at every step)
    elastic = ca.if_else(q > 0, K * ca.fmax(q, 1e-300)**exponent, 0.0)
    if law == "hertz":
        return elastic
    return ca.fmax(elastic * (1 + d * qdot / qdot_minus), 0.0)


def hertz_stiffness(kind: str, E1: float, nu1: float, E2: float, nu2: float, R_pin: float,
                    R_other: float | None, radius: str, length: float | None) -> float:
    """K of Eq. 14 (spheres) or Eq. 16 (cylinders, pi E* L / 4), SI. R_other is the hole's or
    the other circle's radius (None: a line, an infinite radius)."""
    sigma = (1 - nu1**2) / E1 + (1 - nu2**2) / E2
    if kind == "cylinders":
        return math.pi / 4 / sigma * length
    if R_other is None:
        effective = R_pin
    elif radius == "external":
        effective = R_pin * R_other / (R_pin + R_other)
    else:
        effective = R_pin * R_other / abs(R_other - R_pin)
    return 4 / (3 * sigma) * math.sqrt(effective)


def ambrosio_friction(v_T, F_N, sliding, v0, v1, beyond_v0, beyond_v1):
    """F_T of Eq. 26 along t_c; the regime (|v_T| beyond v0, beyond v1) is given by flags
    that the integrator switches at located events, so the force is smooth within a step."""
    ramp = ca.fmin(ca.fmax((ca.fabs(v_T) - v0) / (v1 - v0), 0.0), 1.0)  # flags switch with a hysteresis
    scale = ca.if_else(beyond_v1, 1.0, ca.if_else(beyond_v0, ramp, 0.0))
    return -scale * sliding * F_N * ca.sign(v_T)


def effective_restitution(d: float) -> float:
    """The exact rebound ratio of one degree of freedom under F = K x^n (1 + d xdot / v-),
    independent of K, n and the mass: u du / (1 + d u) = -x^n dx integrates in closed form,
    Phi(u) = u / d - ln(1 + d u) / d^2, and the exit speed e solves Phi(-e) = Phi(1)."""
    if d == 0:
        return 1.0

    def phi(u):
        return u / d - math.log1p(d * u) / d**2

    target = phi(1.0)
    lo, hi = 0.0, min(1.0, (1 - 1e-15) / d)
    for _ in range(200):  # bisection: phi(-e) grows with e on (0, 1/d)
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if phi(-mid) < target else (lo, mid)
    return 0.5 * (lo + hi)
