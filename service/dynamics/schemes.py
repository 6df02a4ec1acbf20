"""Time-integration schemes of the Newmark family, as generalized-alpha parameters (Chung and
Hulbert 1993; the form of Arnold and Bruls 2007, with an acceleration-like variable a):

    (1 - alpha_m) a_{n+1} + alpha_m a_n = (1 - alpha_f) qdd_{n+1} + alpha_f qdd_n
    x_{n+1} = x_n + h v_n + h^2 ((1/2 - beta) a_n + beta a_{n+1})
    v_{n+1} = v_n + h ((1 - gamma) a_n + gamma a_{n+1})

Newmark is alpha_m = alpha_f = 0 (average acceleration: gamma = 1/2, beta = 1/4, which keeps
the energy of a linear undamped system); generalized-alpha is second order with the spectral
radius rho_inf of its high-frequency response as its one parameter (1: no dissipation)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Scheme:
    name: str
    alpha_m: float
    alpha_f: float
    gamma: float
    beta: float

    @property
    def order(self) -> int:
        """2 when gamma = 1/2 + alpha_f - alpha_m, else 1."""
        return 2 if abs(self.gamma - (0.5 + self.alpha_f - self.alpha_m)) < 1e-12 else 1


def newmark(gamma: float = 0.5, beta: float = 0.25) -> Scheme:
    """Unconditionally stable for gamma >= 1/2 and beta >= gamma / 2 (Hughes 2000, Sec. 9.1);
    beta >= (gamma + 1/2)^2 / 4 also damps the highest frequencies most, not a stability bound."""
    if not (gamma >= 0.5 and beta >= 0.5 * gamma - 1e-15):
        raise ValueError(
            f"Newmark gamma = {gamma:g}, beta = {beta:g} is not unconditionally stable "
            "(gamma >= 1/2 and beta >= gamma / 2)"
        )
    return Scheme("newmark", 0.0, 0.0, gamma, beta)


def generalized_alpha(rho_inf: float = 0.9) -> Scheme:
    if not 0.0 <= rho_inf <= 1.0:
        raise ValueError(f"rho_inf must lie in [0, 1], got {rho_inf:g}")
    alpha_m = (2 * rho_inf - 1) / (rho_inf + 1)
    alpha_f = rho_inf / (rho_inf + 1)
    gamma = 0.5 + alpha_f - alpha_m
    return Scheme("generalized_alpha", alpha_m, alpha_f, gamma, 0.25 * (gamma + 0.5) ** 2)
