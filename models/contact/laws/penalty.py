"""Penalty normal laws (seed 004 Eqs. 13-25): a force of the indentation q >= 0, its rate
qdot (positive while the surfaces approach) and the rate frozen at the contact's onset,
qdot_minus; Hertz's stiffness from geometry and materials (Eqs. 14-17); the ESDU-78035 law
of a pin in a hole (Eq. 18) solved exactly; and a linear spring-dashpot."""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca

from flexmech.models.contact.laws.registry import NormalLaw

EVENT_DRIVEN = frozenset({"event_driven"})
POWER_LAW_NEEDS = ("stiffness", "exponent", "restitution")
# Newton steps on the ESDU law in log form: from the asymptotic start, 6 reach machine
# precision for every indentation the law covers (tested against scipy's Lambert W).
ESDU_NEWTON_STEPS = 6


def elastic_power(K, q, exponent):
    """K q^n for q >= 0: 0 at q = 0 exactly as 0^n, with derivatives that stay finite there
    (q^n's by n is q^n ln q, 0 * -inf; a run's sensitivities differentiate the law)."""
    return ca.if_else(q > 0, K * ca.fmax(q, 1e-300) ** exponent, 0.0)


LINK_DYNAMICS = frozenset({"event_driven", "link_dynamics"})  # link dynamics locates their onsets


@dataclass(frozen=True)
class DampedPowerLaw(NormalLaw):
    """F = K q^n (1 + d qdot / qdot_minus), d from the restitution c_r (Eqs. 21-23)."""

    name: str = "damped_power"
    analyses: frozenset[str] = LINK_DYNAMICS
    summary: str = ""
    needs: tuple[str, ...] = POWER_LAW_NEEDS

    def damping_factor(self, restitution):
        """d of the law from c_r; each damped law gives its own (Eqs. 21-23)."""
        raise TypeError(
            f"{type(self).__name__} is the damped laws' shape, not a law: register one of its "
            "subclasses, which give damping_factor"
        )

    def force(self, pair, q, rate, impact_speed):
        d = self.damping_factor(pair.restitution)
        elastic = elastic_power(pair.K, ca.fmax(q, 0.0), pair.exponent)
        return ca.fmax(elastic * (1 + d * rate / impact_speed), 0.0)


@dataclass(frozen=True)
class Hertz(DampedPowerLaw):
    """Elastic: the gradient of K q^(n+1) / (n+1), so the statics and link dynamics take it too
    (models.contact.elastic_pairs)."""

    name: str = "hertz"
    analyses: frozenset[str] = LINK_DYNAMICS
    summary: str = "F = K q^n, elastic (Eq. 13)"
    needs: tuple[str, ...] = ("stiffness", "exponent")

    def damping_factor(self, restitution):
        return 0.0

    def force(self, pair, q, rate, impact_speed):
        return elastic_power(pair.K, ca.fmax(q, 0.0), pair.exponent)


@dataclass(frozen=True)
class HuntCrossley(DampedPowerLaw):
    name: str = "hunt_crossley"
    summary: str = "Hunt-Crossley, d = 3 (1 - c_r) / 2 (Eq. 21)"

    def damping_factor(self, restitution):
        return 1.5 * (1 - restitution)


@dataclass(frozen=True)
class LankaraniNikravesh(DampedPowerLaw):
    name: str = "lankarani_nikravesh"
    summary: str = "Lankarani-Nikravesh, d = 3 (1 - c_r^2) / 4 (Eq. 22)"

    def damping_factor(self, restitution):
        return 0.75 * (1 - restitution**2)


@dataclass(frozen=True)
class Flores(DampedPowerLaw):
    name: str = "flores"
    summary: str = "Flores, d = 8 (1 - c_r) / (5 c_r) (Eq. 23)"

    def damping_factor(self, restitution):
        return 8 * (1 - restitution) / (5 * restitution)


@dataclass(frozen=True)
class LnaEsdu(LankaraniNikravesh):
    """Eq. 24 read as F_E(q) + d K_ESDU(q) q qdot / qdot_minus: the ESDU elastic force with
    Lankarani-Nikravesh damping at the ESDU tangent stiffness (Eq. 24 as printed lacks the q
    that makes its damping term a force). A pin in a hole only."""

    name: str = "lna_esdu"
    analyses: frozenset[str] = EVENT_DRIVEN  # its elastic part has no closed-form potential
    summary: str = "ESDU-78035 of a pin in a hole with Lankarani-Nikravesh damping (Eqs. 18, 24)"
    needs: tuple[str, ...] = ("restitution", "length", "materials")

    def force(self, pair, q, rate, impact_speed):
        d = self.damping_factor(pair.restitution)
        q = ca.fmax(q, 0.0)
        elastic, tangent = esdu_force(q, *pair.esdu)
        return ca.fmax(elastic + d * tangent * q * rate / impact_speed, 0.0)


@dataclass(frozen=True)
class LinearSpringDashpot(NormalLaw):
    """F = K q + c qdot (Kelvin-Voigt), never pulling: it ends where the dashpot would pull."""

    name: str = "linear"
    analyses: frozenset[str] = EVENT_DRIVEN  # its force jumps at the onset: implicit steps may find no root
    summary: str = "linear spring-dashpot, F = K q + c qdot (K in force / length, c in force s / length)"
    needs: tuple[str, ...] = ("stiffness", "damping")

    def force(self, pair, q, rate, impact_speed):
        return ca.fmax(pair.K * ca.fmax(q, 0.0) + pair.damping * rate, 0.0)


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


def hertz_stiffness(
    kind: str,
    E1: float,
    nu1: float,
    E2: float,
    nu2: float,
    R_pin: float,
    R_other: float | None,
    radius: str,
    length: float | None,
) -> float:
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
