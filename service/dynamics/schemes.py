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


@dataclass(frozen=True)
class StageScheme:
    """A singly diagonally implicit Runge-Kutta scheme (SDIRK), stiffly accurate: every stage is
    one implicit solve for that stage's accelerations with the same diagonal a_ii = gamma, so that
    on a second-order system (x' = v, v' = a) stage i reads

        V_i = v_n + h sum_j a_ij A_j,    X_i = x_n + h c_i v_n + h^2 sum_j (a^2)_ij A_j,

    affine in A_i with the coefficients h gamma and h^2 gamma^2 at every stage: one factorization
    serves all of them. The step ends at the last stage (x_{n+1} = X_s, v_{n+1} = V_s)."""

    name: str
    a: tuple[tuple[float, ...], ...]  # lower triangular, a[i][i] = gamma
    embedded: tuple[float, ...]  # weights of the embedded solution of order `order` - 1
    order: int

    @property
    def stages(self) -> int:
        return len(self.a)

    @property
    def gamma(self) -> float:
        return self.a[0][0]

    @property
    def nodes(self) -> tuple[float, ...]:
        return tuple(sum(row) for row in self.a)

    @property
    def weights(self) -> tuple[float, ...]:
        return self.a[-1]  # stiffly accurate

    @property
    def error_weights(self) -> tuple[float, ...]:
        """d: the positions' local error estimate h^2 sum_j d_j A_j, the step's positions less the
        embedded solution's, d = (b - b_embedded) a."""
        s = self.stages
        return tuple(sum((self.weights[i] - self.embedded[i]) * self.a[i][j] for i in range(s)) for j in range(s))

    @property
    def squared(self) -> tuple[tuple[float, ...], ...]:
        """a^2: the positions' coefficients of the stage accelerations."""
        s = self.stages
        return tuple(tuple(sum(self.a[i][k] * self.a[k][j] for k in range(s)) for j in range(s)) for i in range(s))


def sdirk4() -> StageScheme:
    """The L-stable, stiffly accurate SDIRK of order 4 with gamma = 1/4 and an embedded solution
    of order 3 (Hairer and Wanner 1996, Sec. IV.6, Table 6.5; their code SDIRK4)."""
    a = (
        (1 / 4, 0.0, 0.0, 0.0, 0.0),
        (1 / 2, 1 / 4, 0.0, 0.0, 0.0),
        (17 / 50, -1 / 25, 1 / 4, 0.0, 0.0),
        (371 / 1360, -137 / 2720, 15 / 544, 1 / 4, 0.0),
        (25 / 24, -49 / 48, 125 / 16, -85 / 12, 1 / 4),
    )
    return StageScheme("sdirk4", a, (59 / 48, -17 / 96, 225 / 32, -85 / 12, 0.0), 4)
