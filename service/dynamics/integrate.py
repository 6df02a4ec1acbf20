"""Time integration of the dynamics form: each step solves for the accelerations and the
constraint forces at the step's end by Newton with the exact Jacobian (one CasADi Function
per structure and scheme), the constraints held at position level (scaled by 1 / (beta h^2)).
A step that does not converge ends the run with its status and the history so far."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import lru_cache

import casadi as ca
import numpy as np

from models.dynamics import DynamicsForm, dynamics_form
from models.structure import Structure
from service.dynamics.schemes import Scheme

NEWTON_TOLERANCE = 1e-10  # nondimensional residual of a step's equations (forces)
CONSTRAINT_TOLERANCE = 1e-13  # and of its constraints (lengths, angles)
MAX_NEWTON = 25


@dataclass
class History:
    status: str  # finished | not_converged | stopped
    message: str
    times: list[float] = field(default_factory=list)
    x: list[np.ndarray] = field(default_factory=list)
    v: list[np.ndarray] = field(default_factory=list)
    acceleration: list[np.ndarray] = field(default_factory=list)
    lam: list[np.ndarray] = field(default_factory=list)
    kinetic: list[float] = field(default_factory=list)
    potential: list[float] = field(default_factory=list)
    newton_iterations: int = 0
    seconds: float = 0.0


@lru_cache(maxsize=16)
def form_of(structure: Structure) -> DynamicsForm:
    return dynamics_form(structure)


@lru_cache(maxsize=16)
def step_function(structure: Structure, scheme: Scheme) -> ca.Function:
    """(u = [qdd1; lam1], x, v, a, qdd, h, p, damping) -> (F, dF/du, x1, v1, a1)."""
    form = form_of(structure)
    n, m = len(form.unknowns), form.n_equalities
    u = ca.SX.sym("u", n + m)
    qdd1, lam1 = u[:n], u[n:]
    x, v, a, qdd = (ca.SX.sym(name, n) for name in ("x", "v", "a", "qdd"))
    h, damping = ca.SX.sym("h"), ca.SX.sym("damping")
    p = ca.SX.sym("p", form.constraints.size1_in(1))
    s = scheme
    a1 = ((1 - s.alpha_f) * qdd1 + s.alpha_f * qdd - s.alpha_m * a) / (1 - s.alpha_m)
    x1 = x + h * v + h**2 * ((0.5 - s.beta) * a + s.beta * a1)
    v1 = v + h * ((1 - s.gamma) * a + s.gamma * a1)
    F = ca.vertcat(form.equations(x1, v1, qdd1, lam1, p, damping), form.constraints(x1, p) / (s.beta * h**2))
    return ca.Function("step", [u, x, v, a, qdd, h, p, damping], [F, ca.jacobian(F, u), x1, v1, a1],
                       ["u", "x", "v", "a", "qdd", "h", "p", "damping"], ["F", "J", "x1", "v1", "a1"])


def consistent_acceleration(form: DynamicsForm, x: np.ndarray, v: np.ndarray, p: np.ndarray,
                            damping: float) -> tuple[np.ndarray, np.ndarray]:
    """(qdd, lam) that satisfy the equations and the constraints' second derivative at (x, v)."""
    n, m = len(form.unknowns), form.n_equalities
    M = np.asarray(form.mass(x, p), dtype=float)
    rest = np.asarray(form.equations(x, v, np.zeros(n), np.zeros(m), p, damping), dtype=float).ravel()
    G = np.asarray(form.constraint_jacobian(x, p), dtype=float).reshape(m, n)
    drift = np.asarray(form.constraint_drift(x, v, p), dtype=float).ravel()
    K = np.block([[M, G.T], [G, np.zeros((m, m))]])
    solution = np.linalg.solve(K, np.concatenate([-rest, -drift]))
    return solution[:n], solution[n:]


def integrate(structure: Structure, p: np.ndarray, x0: np.ndarray, v0: np.ndarray, until: float, h: float,
              scheme: Scheme, damping: float = 0.0, every: int = 1, stop=None) -> History:
    """States from t = 0 to `until` in steps h (seconds), keeping every `every`-th."""
    started = time.perf_counter()
    form = form_of(structure)
    step = step_function(structure, scheme)
    n = len(form.unknowns)
    x, v = np.asarray(x0, dtype=float).copy(), np.asarray(v0, dtype=float).copy()
    qdd, lam = consistent_acceleration(form, x, v, p, damping)
    a = qdd.copy()
    history = History("finished", "")
    _keep(history, form, 0.0, x, v, qdd, lam, p)
    steps = int(round(until / h))
    for k in range(1, steps + 1):
        if stop is not None and stop():
            history.status, history.message = "stopped", f"stopped at t = {(k - 1) * h:g} s"
            break
        u = np.concatenate([qdd, lam])
        for iteration in range(MAX_NEWTON):
            F, J, x1, v1, a1 = step(u, x, v, a, qdd, h, p, damping)
            F = np.asarray(F, dtype=float).ravel()
            history.newton_iterations += 1
            if (np.abs(F[:n]).max(initial=0.0) <= NEWTON_TOLERANCE
                    and np.abs(F[n:]).max(initial=0.0) * scheme.beta * h**2 <= CONSTRAINT_TOLERANCE):
                break
            u = u - np.linalg.solve(np.asarray(J, dtype=float), F)
        else:
            history.status = "not_converged"
            history.message = f"the step to t = {k * h:g} s did not converge (residual {np.abs(F[:n]).max():.3g})"
            break
        x, v, a = (np.asarray(q, dtype=float).ravel() for q in (x1, v1, a1))
        qdd, lam = u[:n], u[n:]
        if k % every == 0 or k == steps:
            _keep(history, form, k * h, x, v, qdd, lam, p)
    history.seconds = time.perf_counter() - started
    return history


def _keep(history: History, form: DynamicsForm, t, x, v, qdd, lam, p) -> None:
    T, V = form.energies(x, v, p)
    history.times.append(t)
    history.x.append(x.copy())
    history.v.append(v.copy())
    history.acceleration.append(qdd.copy())
    history.lam.append(lam.copy())
    history.kinetic.append(float(T))
    history.potential.append(float(V))
