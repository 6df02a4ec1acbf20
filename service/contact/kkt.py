"""Newton's method on the contact problem's active-set KKT system (service.contact.problem),
with the active set corrected until it is consistent: active rows push (lam >= 0), inactive
rows are apart (h >= 0). Used to polish IPOPT's solution to rounding level, to add friction,
and for sensitivities."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from flexmech.service.contact.problem import ContactProblem

NEWTON_TOLERANCE = 1e-11  # on the nondimensional KKT residual
ROUNDING_FLOOR = 1e-8  # below this, a residual that no longer falls has reached rounding (ill-conditioned KKT)
CONSISTENCY = 1e-10  # how negative a multiplier or a gap may be (rounding)


@dataclass
class Mode:
    """What the KKT system assumes: active rows, frictional rows and sticking pairs, frozen
    separating axes (their pairs touch nowhere), and the reference state of the step."""

    active: np.ndarray  # per inequality row, 1 active
    phi: np.ndarray  # per inequality row: mu sigma at slipping rows, else 0
    freeze: np.ndarray  # per axis variable, 1 frozen at ref
    ref: np.ndarray
    stick: np.ndarray  # per pair, 1 sticking
    weights: np.ndarray  # per contact row, its share of its pair's normal force
    points_old: np.ndarray  # (2, rows) the site points at the reference state
    origins_old: np.ndarray  # (2, objects)
    angles_old: np.ndarray

    def arguments(self, v: np.ndarray, p: np.ndarray) -> dict:
        return {
            "v": v,
            "p": p,
            "active": self.active,
            "phi": self.phi,
            "freeze": self.freeze,
            "ref": self.ref,
            "stick": self.stick,
            "weights": self.weights,
            "points_old": self.points_old,
            "origins_old": self.origins_old,
            "angles_old": self.angles_old,
        }


@dataclass
class Split:
    w: np.ndarray
    lam_eq: np.ndarray
    lam_in: np.ndarray
    tau: np.ndarray


def split(problem: ContactProblem, v: np.ndarray) -> Split:
    a = problem.n_w
    b = a + problem.n_eq
    c = b + problem.n_in
    return Split(v[:a], v[a:b], v[b:c], v[c:])


@dataclass
class NewtonRun:
    converged: bool
    v: np.ndarray
    norm: float
    iterations: int
    history: list[float] = field(default_factory=list)


def newton(problem: ContactProblem, v: np.ndarray, p: np.ndarray, mode: Mode, max_iterations: int = 30) -> NewtonRun:
    v = v.copy()
    history = []
    for iteration in range(max_iterations + 1):
        F, J = _kkt(problem, v, p, mode)
        norm = float(np.abs(F).max(initial=0.0))
        history.append(norm)
        stalled = len(history) > 3 and norm <= ROUNDING_FLOOR and norm > 0.5 * min(history[-4:-1])
        if norm <= NEWTON_TOLERANCE or stalled or not np.isfinite(norm):
            return NewtonRun(bool(np.isfinite(norm)), v, norm, iteration, history)
        if iteration == max_iterations:
            break
        try:
            step = np.linalg.solve(J, -F)
        except np.linalg.LinAlgError:  # dependent active rows (a degenerate contact): the least-norm step
            step = np.linalg.lstsq(J, -F, rcond=None)[0]
        v = v + step
    return NewtonRun(False, v, norm, max_iterations, history)


def _kkt(problem: ContactProblem, v: np.ndarray, p: np.ndarray, mode: Mode) -> tuple[np.ndarray, np.ndarray]:
    out = problem.kkt(**mode.arguments(v, p))
    return np.asarray(out["F"], dtype=float).ravel(), np.asarray(out["J"], dtype=float)


def residual(problem: ContactProblem, v: np.ndarray, p: np.ndarray, mode: Mode) -> np.ndarray:
    return _kkt(problem, v, p, mode)[0]


def freeze_untouched_axes(problem: ContactProblem, mode: Mode, v: np.ndarray) -> Mode:
    """Axes of pairs with no active row are held where they are (nothing else fixes them)."""
    if not problem.n_axes:
        return mode
    touching = {problem.row_pairs[k] for k in range(problem.n_rows) if mode.active[problem.n_element_in + k] > 0.5}
    freeze = np.array([0.0 if problem.axis_pairs[j // 2] in touching else 1.0 for j in range(problem.n_axes)])
    return replace(mode, freeze=freeze, ref=v[problem.n_x : problem.n_w].copy())


def consistent_active_set(
    problem: ContactProblem, v: np.ndarray, p: np.ndarray, mode: Mode, rounds: int = 12
) -> tuple[NewtonRun, Mode]:
    """Newton, then correct the active set (drop pulling rows, add penetrating ones) and
    repeat until both hold; the last run and mode."""
    run = None
    for _ in range(rounds):
        mode = freeze_untouched_axes(problem, mode, v)
        run = newton(problem, v, p, mode)
        if not run.converged:
            return run, mode
        v = run.v
        parts = split(problem, v)
        h = inequality_values(problem, parts.w, p)
        pulling = (mode.active > 0.5) & (parts.lam_in < -CONSISTENCY)
        penetrating = (mode.active < 0.5) & (h < -CONSISTENCY)
        if not pulling.any() and not penetrating.any():
            return run, mode
        active = mode.active.copy()
        active[pulling] = 0.0
        active[penetrating] = 1.0
        mode = replace(mode, active=active)
    return NewtonRun(False, run.v, run.norm, run.iterations, run.history), mode


def inequality_values(problem: ContactProblem, w: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Every inequality row's h (elements' rows first, unshifted)."""
    x = w[: problem.n_x]
    element = (
        np.asarray(problem.element_inequalities(x, p), dtype=float).ravel() if problem.n_element_in else np.zeros(0)
    )
    contact = np.asarray(problem.rows(w, p)[0], dtype=float).ravel()
    return np.concatenate([element, contact])
