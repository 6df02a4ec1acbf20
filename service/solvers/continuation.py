"""Pseudo-arc-length continuation along a load (or any numeric field) through limit points.

The path is followed in (z, lambda), lambda the field's nondimensional value: a predictor
along the unit tangent, then Newton on R(z, lambda) = 0 plus the hyperplane through the
predicted point normal to the tangent (Keller). The tangent's lambda component changes sign
exactly at a limit point; each one bracketed so is located by Newton on the extended system
R = 0, K phi = 0, l.phi = 1 (Moore-Spence), so its load is exact to the solver's tolerance.

Stability of each point: the tangent stiffness over the body coordinates (the links'
shooting unknowns condensed out) is positive definite where symmetric (a conservative
system), else its eigenvalues' real parts are positive.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.graph.assembly import graphs_for
from flexmech.models.graph.structure import Structure
from flexmech.service.solvers.newton import NewtonOptions, iterate_dense
from flexmech.service.units import outputs_in_doc_units

CORRECTOR_ITERATIONS = 12


@dataclass
class Stability:
    stable: bool | None  # None: the stiffness is singular here
    symmetric: bool
    eigenvalues: list[float]  # of the body stiffness, nondimensional, ascending (real parts if not symmetric)


@dataclass
class PathPoint:
    value: float  # the field, document units
    z: np.ndarray = field(repr=False)
    tangent_value: float  # d(lambda)/ds: its sign says whether the load rises along the path
    stability: Stability
    outputs: dict[str, float] = field(repr=False)


@dataclass
class LimitPoint:
    value: float  # document units
    after_point: int  # index of the path point just before it
    z: np.ndarray = field(repr=False)
    residual: float
    outputs: dict[str, float] = field(repr=False)
    kind: str  # maximum | minimum of the field along the path


@dataclass
class PathResult:
    status: str  # completed | not_converged | max_points
    message: str
    path: str
    unit: str
    points: list[PathPoint]
    limit_points: list[LimitPoint]
    seconds: float

    def to_dict(self, outputs: list[str] | None = None) -> dict:
        def pick(values):
            return {k: v for k, v in values.items() if outputs is None or k in outputs}

        return {
            "status": self.status,
            "message": self.message,
            "path": self.path,
            "unit": self.unit,
            "seconds": self.seconds,
            "points": [
                {
                    "value": p.value,
                    "rising": p.tangent_value > 0,
                    "stable": p.stability.stable,
                    "eigenvalues": p.stability.eigenvalues,
                    "outputs": pick(p.outputs),
                }
                for p in self.points
            ],
            "limit_points": [
                {
                    "value": lp.value,
                    "kind": lp.kind,
                    "after_point": lp.after_point,
                    "residual": lp.residual,
                    "outputs": pick(lp.outputs),
                }
                for lp in self.limit_points
            ],
        }


@lru_cache(maxsize=16)
def _path_graphs(structure: Structure, slot: int) -> tuple[ca.Function, ca.Function]:
    """(z, lam, p) -> (R, K, dR/dlam) and the extended system of a limit point
    (z, lam, phi, l, p) -> (F, dF/d(z, lam, phi)), for the field in parameter `slot`."""
    g = graphs_for(structure)
    n = structure.n_unknowns
    z, lam, phi, ell = ca.SX.sym("z", n), ca.SX.sym("lam"), ca.SX.sym("phi", n), ca.SX.sym("l", n)
    p = ca.SX.sym("p", len(structure.parameters))
    p_lam = ca.SX(p)
    p_lam[slot] = lam
    R, K = g.residual_and_tangent(z, p_lam)
    path = ca.Function(
        "path", [z, lam, p], [R, K, ca.jacobian(R, lam)], ["z", "lam", "p"], ["R", "K", "R_lam"], dict(cse=True)
    )
    F = ca.vertcat(R, K @ phi, ca.dot(ell, phi) - 1)
    unknowns = ca.vertcat(z, lam, phi)
    fold = ca.Function(
        "limit_point",
        [z, lam, phi, ell, p],
        [F, ca.jacobian(F, unknowns)],
        ["z", "lam", "phi", "l", "p"],
        ["F", "J"],
        dict(cse=True),
    )
    return path, fold


def body_stability(mech: Mechanism, K: np.ndarray) -> Stability:
    """Definiteness of the body stiffness (links condensed out) where it is symmetric, else
    the real parts of its eigenvalues."""
    from flexmech.service.solvers.stiffness import condensed

    try:
        Kb = condensed(K, mech.n_body_coordinates)
    except (MechanismError, np.linalg.LinAlgError):
        return Stability(None, False, [])
    if not np.all(np.isfinite(Kb)):
        return Stability(None, False, [])
    scale = max(np.abs(Kb).max(), 1e-300)
    symmetric = bool(np.abs(Kb - Kb.T).max() <= 1e-6 * scale)
    if symmetric:
        eig = np.linalg.eigvalsh((Kb + Kb.T) / 2)
    else:
        eig = np.sort(np.linalg.eigvals(Kb).real)
    return Stability(bool(eig[0] > 0), symmetric, eig.tolist())


@dataclass
class _Trace:
    """The followed field: its slot, document factor and unit, the parameters, and the stop."""

    slot: int
    factor: float
    unit: str
    p: np.ndarray
    target: float  # nondimensional
    direction: float  # +1: the field rises towards the stop
    path_fn: ca.Function

    def evaluate_at(self, lam_value: float):
        def evaluate(z):
            R, K, _ = self.path_fn(z, lam_value, self.p)
            return np.asarray(R).ravel(), np.asarray(K)

        return evaluate


def _trace(mech: Mechanism, path: str, stop: float, step: float) -> _Trace:
    slot = mech.parameter_index(path)
    kind = mech.parameters[slot].kind
    factor, unit = mech.nd_per_doc(kind), mech.doc_unit(kind)
    if not step > 0:
        raise MechanismError("/step", f"must be positive, got {step:g}")
    p = mech.p()
    target = stop * factor
    if target == float(p[slot]):
        raise MechanismError("/stop", f"the path starts at {stop:g} {unit}: give another stop value")
    return _Trace(
        slot, factor, unit, p, target, 1.0 if target > p[slot] else -1.0, _path_graphs(mech.structure.unnamed, slot)[0]
    )


def trace_path(
    mech: Mechanism,
    path: str,
    stop: float,
    step: float,
    max_points: int = 400,
    options: NewtonOptions = NewtonOptions(),
    max_step: float | None = None,
    should_stop: Callable[[], bool] | None = None,
) -> PathResult:
    """Follow the equilibrium path from the document's value of `path` until the field passes
    `stop` (document units), through any limit points. `step`: first arc-length step, in
    document units of the field (the arc length also counts the nondimensional state, so
    steps near limit points move the state rather than the load); max_step caps it (default
    10 x step). should_stop() is asked before each point: True ends the path as "stopped"
    (a time limit, a cancel) with the points so far."""
    started = time.perf_counter()
    t = _trace(mech, path, stop, step)
    slot, factor, unit, p, path_fn, direction = t.slot, t.factor, t.unit, t.p, t.path_fn, t.direction
    n, lam = mech.n_free, float(t.p[t.slot])
    status, z, *_ = iterate_dense(t.evaluate_at(lam), np.zeros(n), options)
    if status != "converged":
        return _ended("not_converged", f"no equilibrium at the start value ({status})", path, unit, [], [], started)
    ds, ds_max = step * factor, (max_step if max_step is not None else 10 * step) * factor
    ds_min = ds * 1e-6
    tangent = _tangent(path_fn, z, lam, p, None, direction)
    points = [_point(mech, path_fn, z, lam, p, slot, tangent, factor)]
    limits: list[LimitPoint] = []
    while len(points) < max_points:
        if should_stop is not None and should_stop():
            message = f"stopped after {len(points)} points at {lam / factor:.6g} {unit}"
            return _ended("stopped", message, path, unit, points, limits, started)
        x = np.append(z, lam)
        ok, x_new, iterations = _correct(path_fn, x + ds * tangent, tangent, p, options)
        if not ok:
            ds /= 2
            if ds < ds_min:
                message = f"the corrector failed at {lam / factor:.6g} {unit} even with tiny steps"
                return _ended("not_converged", message, path, unit, points, limits, started)
            continue
        new_tangent = _tangent(path_fn, x_new[:n], x_new[n], p, tangent, direction)
        if (x_new[n] - t.target) * direction >= 0 and new_tangent[n] * direction > 0:
            # Passed the stop value while rising: end exactly on it.
            if _end_on_stop(mech, t, x, x_new, tangent, new_tangent, points, limits, options):
                return _ended("completed", "", path, unit, points, limits, started)
        if np.sign(new_tangent[n]) != np.sign(tangent[n]):
            limits.append(_limit(mech, x, x_new, tangent, len(points) - 1, p, slot, factor, options))
        z, lam, tangent = x_new[:n], float(x_new[n]), new_tangent
        points.append(_point(mech, path_fn, z, lam, p, slot, tangent, factor))
        ds = min(ds * 1.5, ds_max) if iterations <= 3 else (ds / 1.5 if iterations > 6 else ds)
    message = f"stopped after {max_points} points at {lam / factor:.6g} {unit}"
    return _ended("max_points", message, path, unit, points, limits, started)


def _ended(
    status: str, message: str, path: str, unit: str, points: list[PathPoint], limits: list[LimitPoint], started: float
) -> PathResult:
    """The path as far as it went, and the seconds since `started`."""
    return PathResult(status, message, path, unit, points, limits, time.perf_counter() - started)


def _end_on_stop(
    mech: Mechanism,
    t: _Trace,
    x: np.ndarray,
    x_new: np.ndarray,
    tangent: np.ndarray,
    new_tangent: np.ndarray,
    points: list[PathPoint],
    limits: list[LimitPoint],
    options: NewtonOptions,
) -> bool:
    """The last point exactly on the stop value, between path points x and x_new (and a limit
    point between them, if the path turned), added to points and limits; False if Newton
    does not converge there."""
    n = mech.n_free
    status, z_end, *_ = iterate_dense(t.evaluate_at(t.target), _interpolate(x, x_new, t.target, n), options)
    if status != "converged":
        return False
    if np.sign(new_tangent[n]) != np.sign(tangent[n]):
        limits.append(_limit(mech, x, x_new, tangent, len(points) - 1, t.p, t.slot, t.factor, options))
    points.append(_point(mech, t.path_fn, z_end, t.target, t.p, t.slot, new_tangent, t.factor))
    return True


def _interpolate(x0: np.ndarray, x1: np.ndarray, lam: float, n: int) -> np.ndarray:
    t = (lam - x0[n]) / (x1[n] - x0[n])
    return x0[:n] + t * (x1[:n] - x0[:n])


def _tangent(path_fn, z, lam, p, previous: np.ndarray | None, direction: float) -> np.ndarray:
    """Unit tangent of the path, oriented along the previous one (first: lambda towards the stop)."""
    _, K, R_lam = (np.asarray(a) for a in path_fn(z, lam, p))
    n = K.shape[0]
    if previous is None:
        t = np.append(np.linalg.solve(K, -R_lam.ravel()), 1.0) * direction
    else:
        A = np.vstack([np.hstack([K, R_lam]), previous[None, :]])
        t = np.linalg.solve(A, np.append(np.zeros(n), 1.0))
    return t / np.linalg.norm(t)


def _correct(path_fn, predicted, tangent, p, options: NewtonOptions):
    """Newton on R = 0 and tangent . (x - predicted) = 0."""
    n = len(predicted) - 1
    x = predicted.copy()
    for k in range(CORRECTOR_ITERATIONS + 1):
        R, K, R_lam = (np.asarray(a) for a in path_fn(x[:n], x[n], p))
        H = np.append(R.ravel(), tangent @ (x - predicted))
        if not np.all(np.isfinite(H)):
            return False, x, k
        if np.abs(H).max() <= options.tol_residual and k > 0:
            return True, x, k
        if k == CORRECTOR_ITERATIONS:
            break
        J = np.vstack([np.hstack([K, R_lam]), tangent[None, :]])
        try:
            dx = np.linalg.solve(J, -H)
        except np.linalg.LinAlgError:
            return False, x, k
        x = x + dx
        if np.abs(dx).max() <= options.tol_step * 1e-3:
            R = np.asarray(path_fn(x[:n], x[n], p)[0]).ravel()
            return bool(np.abs(R).max() <= options.tol_residual), x, k + 1
    return False, x, CORRECTOR_ITERATIONS


def _point(mech, path_fn, z, lam, p, slot, tangent, factor) -> PathPoint:
    _, K, _ = path_fn(z, lam, p)
    p_lam = p.copy()
    p_lam[slot] = lam
    return PathPoint(
        lam / factor,
        z.copy(),
        float(tangent[-1]),
        body_stability(mech, np.asarray(K)),
        outputs_in_doc_units(mech, mech.graphs.outputs(z, p_lam)),
    )


def _limit(mech, x0, x1, tangent0, index, p, slot, factor, options: NewtonOptions) -> LimitPoint:
    """The limit point between two path points: Newton on the extended system from the
    point whose tangent is nearer to vertical, with phi its stiffness' null direction."""
    n = mech.n_free
    path_fn, fold = _path_graphs(mech.structure.unnamed, slot)
    x = (x0 + x1) / 2
    _, K, _ = path_fn(x[:n], x[n], p)
    _, _, vt = np.linalg.svd(np.asarray(K))
    ell = vt[-1]
    w = np.concatenate([x, ell])
    for _ in range(50):
        F, J = (np.asarray(a) for a in fold(w[:n], w[n], w[n + 1 :], ell, p))
        F = F.ravel()
        if np.abs(F).max() <= options.tol_residual:
            break
        w = w + np.linalg.solve(J, -F)
    residual = float(np.abs(np.asarray(fold(w[:n], w[n], w[n + 1 :], ell, p)[0])).max())
    lam = float(w[n])
    kind = "maximum" if tangent0[n] > 0 else "minimum"
    p_lam = p.copy()
    p_lam[slot] = lam
    return LimitPoint(
        lam / factor, index, w[:n].copy(), residual, outputs_in_doc_units(mech, mech.graphs.outputs(w[:n], p_lam)), kind
    )
