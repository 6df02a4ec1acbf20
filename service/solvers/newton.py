"""Damped Newton iteration, and the linear solves it runs on.

The iteration takes a residual R(z) and a direction dz(z, R) (the Newton step -K^-1 R, or
None where K is singular); a backtracking line search on |R|_inf is on by default and can be
switched off to reproduce the paper's plain iteration (seed 000, Algorithm 1). Non-convergence
is a status, never an exception.

The equilibrium's Jacobians are sparse (the shooting blocks of links): sparse_step factors
them sparsely inside CasADi (CSparse LU), with no dense BLAS and no Python per row. The dense
adapter serves the small augmented systems (targets, continuation, the link inverse).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import casadi as ca
import numpy as np

from flexmech.service.buffered import BufferedCall
from flexmech.service.deadline import ends_after, passed

Status = Literal["converged", "not_converged", "singular", "time_limit"]
JacobianChoice = Literal["full", "first_term", "frozen"]

Residual = Callable[[np.ndarray], np.ndarray]
Direction = Callable[[np.ndarray, np.ndarray], "np.ndarray | None"]


@dataclass(frozen=True)
class NewtonOptions:
    """tol_residual and tol_step are on the nondimensional infinity norms (forces in units of
    the largest flexure's EI / r^2, lengths in units of its radius)."""

    tol_residual: float = 1e-10
    tol_step: float = 1e-9
    max_iterations: int = 50
    line_search: bool = True
    jacobian: JacobianChoice = "full"
    time_limit: float | None = None  # seconds of wall time per solve; None: no limit

    def __post_init__(self):
        if self.jacobian not in ("full", "first_term", "frozen"):
            raise ValueError(f"jacobian: unknown choice '{self.jacobian}' (full, first_term, frozen)")
        if self.max_iterations < 1:
            raise ValueError("max_iterations: must be at least 1")
        if self.time_limit is not None and not self.time_limit > 0:
            raise ValueError("time_limit: must be positive")


def _norm(R: np.ndarray) -> float:
    return float(np.abs(R).max()) if R.size else 0.0


def iterate(
    residual: Residual, direction: Direction, z0: np.ndarray, options: NewtonOptions
) -> tuple[Status, np.ndarray, float, int, list[float], str]:
    """Converged when |R|_inf <= tol_residual and the last step |dz|_inf <= tol_step (or the
    guess already satisfies the residual tolerance).
    Returns (status, z, |R|_inf, iterations, residual history, message)."""
    end = ends_after(options.time_limit)
    z = np.array(z0, dtype=float)
    R = residual(z)
    norm = _norm(R)
    step_norm = np.inf
    history: list[float] = []
    for k in range(options.max_iterations + 1):
        history.append(norm)
        if norm <= options.tol_residual and (k == 0 or step_norm <= options.tol_step):
            return "converged", z, norm, k, history, ""
        if not np.isfinite(norm):
            return "not_converged", z, norm, k, history, "residual became non-finite"
        if k == options.max_iterations:
            break
        if passed(end):
            said = (
                f"stopped by the time limit of {options.time_limit:g} s"
                if options.time_limit is not None
                else "stopped: its job was cancelled or ran out of time"
            )
            return "time_limit", z, norm, k, history, said
        dz = direction(z, R)
        if dz is None:
            return "singular", z, norm, k, history, f"tangent stiffness singular at iteration {k}"
        alpha = 1.0
        z_new = z + dz
        R_new = residual(z_new)
        norm_new = _norm(R_new)
        if options.line_search:
            while not (np.isfinite(norm_new) and norm_new <= (1 - 1e-4 * alpha) * norm) and alpha > 1 / 1024:
                alpha /= 2
                z_new = z + alpha * dz
                R_new = residual(z_new)
                norm_new = _norm(R_new)
        step_norm = float(np.abs(alpha * dz).max())
        z, R, norm = z_new, R_new, norm_new
    return (
        "not_converged",
        z,
        norm,
        options.max_iterations,
        history,
        (f"no convergence in {options.max_iterations} iterations"),
    )


def dense_solve(M: np.ndarray, R: np.ndarray) -> np.ndarray | None:
    """-M^-1 R, or None where M is singular."""
    try:
        return np.linalg.solve(M, -R)
    except np.linalg.LinAlgError:
        return None


class Dense:
    """(residual, direction) from evaluate(z) -> (R, K) with a dense K, evaluating each
    point once (the direction reuses the K of the last residual)."""

    def __init__(self, evaluate: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]):
        self._evaluate = evaluate
        self._last: tuple[np.ndarray, np.ndarray] | None = None

    def residual(self, z: np.ndarray) -> np.ndarray:
        R, K = self._evaluate(z)
        self._last = (z.copy(), K)
        return R

    def direction(self, z: np.ndarray, R: np.ndarray) -> np.ndarray | None:
        if self._last is None or not np.array_equal(self._last[0], z):
            self.residual(z)
        return dense_solve(self._last[1], R)


def iterate_dense(evaluate, z0: np.ndarray, options: NewtonOptions):
    """iterate() on evaluate(z) -> (R, K), K dense."""
    system = Dense(evaluate)
    return iterate(system.residual, system.direction, z0, options)


def sparse_step(residual_and_tangent: ca.Function) -> ca.Function:
    """(z, p) -> dz = -K^-1 R, K factored sparsely (CSparse LU) inside CasADi."""
    z = ca.MX.sym("z", residual_and_tangent.size1_in(0))
    p = ca.MX.sym("p", residual_and_tangent.size1_in(1))
    R, K = residual_and_tangent(z, p)
    return ca.Function("newton_step", [z, p], [-ca.solve(K, R, "csparse")], ["z", "p"], ["dz"])


def sparse_direction(step: ca.Function, p: np.ndarray) -> Direction:
    call = BufferedCall(step)  # 30 us a call instead of 80

    def direction(z: np.ndarray, R: np.ndarray) -> np.ndarray | None:
        try:
            dz = call(z, p)[0].ravel()
        except RuntimeError:  # CSparse: "factorization failed, check if Jacobian is singular"
            return None
        return dz if np.all(np.isfinite(dz)) else None

    return direction
