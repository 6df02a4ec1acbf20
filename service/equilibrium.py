"""Newton's method on R(z, p) = 0 with the exact tangent stiffness.

The paper's update strategies are options: the full K_T or its first term K_T^I only, or
K_T frozen at one state (Fig. 11). A backtracking line search on |R|^2 is on by default and
can be switched off to reproduce the paper's plain iteration (Algorithm 1). Non-convergence
is a status in the result, never an exception.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from models import Mechanism, MechanismError
from models.residual import unknown_names as element_unknowns
from service.units import displacement_to_doc, outputs_in_doc_units

# Seed 000, Sec. 2: the constant-stiffness curved beam is faithful up to about +-20 deg.
ROTATION_VALIDITY_DEG = 20.0

Status = Literal["converged", "not_converged", "singular", "time_limit"]
JacobianChoice = Literal["full", "first_term", "frozen"]


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


@dataclass
class EquilibriumResult:
    status: Status
    z: np.ndarray  # free displacements, nondimensional
    residual_norm: float  # nondimensional infinity norm
    iterations: int
    history: list[float]  # residual norm before each iteration
    seconds: float
    mechanism: Mechanism = field(repr=False)
    message: str = ""

    @property
    def converged(self) -> bool:
        return self.status == "converged"

    def _residual_rows(self, coordinate_kinds: tuple[int, ...]) -> float:
        m = self.mechanism
        R = np.asarray(m.graphs.residual(self.z, m.p())).ravel()
        rows = [R[k] for k, (_, c) in enumerate(m.structure.free) if c in coordinate_kinds]
        return float(np.abs(rows).max()) if rows else 0.0

    @property
    def residual_norm_force(self) -> float:
        """Largest unbalanced force, in the document's force unit."""
        return self._residual_rows((0, 1)) / self.mechanism.nd_per_doc("force")

    @property
    def residual_norm_moment(self) -> float:
        """Largest unbalanced moment, in the document's moment unit."""
        return self._residual_rows((2,)) / self.mechanism.nd_per_doc("moment")

    def outputs(self) -> dict[str, float]:
        """Every named scalar (poses, reactions, flexure wrenches and stresses, points) in
        document units."""
        m = self.mechanism
        return outputs_in_doc_units(m, m.graphs.outputs(self.z, m.p()))

    def warnings(self, outputs: dict[str, float] | None = None) -> list[str]:
        """Where the result leaves the range its models are known to hold in (`outputs`: this
        result's outputs() when already at hand)."""
        m = self.mechanism
        notes = []
        rad_per_unit = m.doc_factor("angle")
        for name, value in (outputs if outputs is not None else self.outputs()).items():
            if name.startswith("elements.") and name.endswith(".rotation"):
                degrees = abs(value) * rad_per_unit * 180 / np.pi
                if degrees > ROTATION_VALIDITY_DEG:
                    element = name.split(".")[1]
                    notes.append(f"flexure {element} rotates {degrees:.1f} deg: the constant-stiffness "
                                 f"curved-beam models hold to about {ROTATION_VALIDITY_DEG:.0f} deg (seed 000)")
        return notes

    def displacements(self) -> dict[str, float]:
        return dict(zip(self.mechanism.free_coordinates, displacement_to_doc(self.mechanism, self.z)))

    def summary(self) -> dict:
        m = self.mechanism
        outputs = self.outputs()
        return {
            "status": self.status,
            "message": self.message,
            "iterations": self.iterations,
            "residual_norm": self.residual_norm_force,
            "residual_unit": m.document.units.force,
            "residual_moment": self.residual_norm_moment,
            "residual_moment_unit": m.doc_unit("moment"),
            "seconds": self.seconds,
            "warnings": self.warnings(outputs) if self.converged else [],
            "displacements": self.displacements(),
            "outputs": outputs,
        }


def check_constrained(mech: Mechanism, p: np.ndarray | None = None) -> None:
    """Raise MechanismError if K_T is singular in the undeformed state (a free motion that no
    flexure resists), naming the coordinates that move in the mechanism's free motion."""
    if mech.n_free == 0:
        return
    p = mech.p() if p is None else p
    _, K = mech.graphs.residual_and_tangent(np.zeros(mech.n_free), p)
    K = np.asarray(K)
    sv = np.linalg.svd(K, compute_uv=False)
    if sv[-1] <= 1e-10 * max(sv[0], 1e-300):
        _, _, vt = np.linalg.svd(K)
        modes = vt[sv <= 1e-10 * max(sv[0], 1e-300)]  # every motion nothing resists
        amplitude = np.abs(modes).max(axis=0)
        moving = [name for name, a in zip(mech.free_coordinates, amplitude) if a > 1e-6]
        raise MechanismError(
            "/bodies",
            "under-constrained: the tangent stiffness is singular in the undeformed state; "
            f"nothing resists a motion of {', '.join(moving)} (connect those bodies with flexures or fix them)",
        )


def iterate(evaluate, z0: np.ndarray, options: NewtonOptions, first_term=None,
            frozen_tangent: np.ndarray | None = None) -> tuple[Status, np.ndarray, float, int, list[float], str]:
    """Damped Newton iteration on a residual.

    evaluate(z) -> (R, K) with K = dR/dz; first_term(z) -> K_T^I (for jacobian="first_term").
    Converged when |R|_inf <= tol_residual and the last step |dz|_inf <= tol_step (or the
    guess already satisfies the residual tolerance).
    Returns (status, z, |R|_inf, iterations, residual history, message).
    """
    started = time.perf_counter()
    z = np.array(z0, dtype=float)
    R, K = evaluate(z)
    norm = float(np.abs(R).max()) if R.size else 0.0
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
        if options.time_limit is not None and time.perf_counter() - started > options.time_limit:
            return "time_limit", z, norm, k, history, f"stopped by the time limit of {options.time_limit:g} s"
        if options.jacobian == "full":
            M = K
        elif options.jacobian == "first_term":
            M = first_term(z)
        else:
            M = frozen_tangent
        try:
            dz = np.linalg.solve(M, -R)
        except np.linalg.LinAlgError:
            return "singular", z, norm, k, history, f"tangent stiffness singular at iteration {k}"
        alpha = 1.0
        z_new = z + dz
        R_new, K_new = evaluate(z_new)
        norm_new = float(np.abs(R_new).max())
        if options.line_search:
            while not (np.isfinite(norm_new) and norm_new <= (1 - 1e-4 * alpha) * norm) and alpha > 1 / 1024:
                alpha /= 2
                z_new = z + alpha * dz
                R_new, K_new = evaluate(z_new)
                norm_new = float(np.abs(R_new).max())
        step_norm = float(np.abs(alpha * dz).max())
        z, R, K, norm = z_new, R_new, K_new, norm_new
    return "not_converged", z, norm, options.max_iterations, history, (
        f"no convergence in {options.max_iterations} iterations")


def newton(mech: Mechanism, p: np.ndarray, z0: np.ndarray, options: NewtonOptions,
           frozen_tangent: np.ndarray | None = None) -> EquilibriumResult:
    g = mech.graphs
    started = time.perf_counter()

    def evaluate(z):
        R, K = g.residual_and_tangent(z, p)
        return np.asarray(R).ravel(), np.asarray(K)

    def first_term(z):
        return np.asarray(g.tangent_terms(z, p)[0])

    if options.jacobian == "frozen" and frozen_tangent is None:
        frozen_tangent = evaluate(np.zeros_like(np.asarray(z0, dtype=float)))[1]
    status, z, norm, k, history, message = iterate(evaluate, z0, options, first_term, frozen_tangent)
    return EquilibriumResult(status, z, norm, k, history, time.perf_counter() - started, mech, message)


def solve_equilibrium(mech: Mechanism, options: NewtonOptions = NewtonOptions(),
                      guess: np.ndarray | None = None, frozen_tangent: np.ndarray | None = None,
                      check: bool = True) -> EquilibriumResult:
    """Equilibrium of `mech` under its loads. `guess`: nondimensional free displacements
    (default: the undeformed state)."""
    p = mech.p()
    if check:
        check_constrained(mech, p)
    z0 = np.zeros(mech.n_free) if guess is None else np.asarray(guess, dtype=float)
    if z0.shape != (mech.n_free,):
        raise ValueError(f"guess: expected {mech.n_free} values, got {z0.shape}")
    return newton(mech, p, z0, options, frozen_tangent)


def unknown_names(mech: Mechanism) -> list[str]:
    """A name for every entry of z: the free body coordinates ("tip.x"), then each element's
    own unknowns, e.g. per link its internal force, start rotation and start moment ("L1.h",
    "L1.v", "L1.rotation_start", "L1.M_start") and its inner shooting states ("L1.node3.psi")."""
    return [name for name, _ in element_unknowns(mech.structure)]


def solve_bounded(mech: Mechanism, bounds: dict[str, tuple[float | None, float | None]],
                  options: NewtonOptions = NewtonOptions(), guess: np.ndarray | None = None) -> EquilibriumResult:
    """Equilibrium with bounds on unknowns (seed 002 Sec. 2.2.2, bounded Gauss-Newton): find
    R(z) = 0 inside the bounds with IPOPT and exact derivatives (a feasibility problem: the
    residuals are equality constraints; IPOPT's restoration phase reports an empty set).
    Bounds are in document units (angles: the document's angle unit), keyed by
    unknown_names(); None: unbounded. Where several equilibria exist (a buckled column), the
    bounds pick the branch whose basin holds the start on the bounds."""
    import casadi as ca

    kinds = dict(element_unknowns(mech.structure))
    names = list(kinds)
    lower, upper = np.full(mech.n_free, -np.inf), np.full(mech.n_free, np.inf)
    for name, (lo, hi) in bounds.items():
        if name not in names:
            shown = ", ".join(n for n in names if ".node" not in n)
            raise MechanismError(f"/bounds/{name}", f"not an unknown of this mechanism (unknowns: {shown})")
        scale = mech.nd_per_doc(kinds[name])
        k = names.index(name)
        if lo is not None:
            lower[k] = lo * scale
        if hi is not None:
            upper[k] = hi * scale
        if lower[k] > upper[k]:
            raise MechanismError(f"/bounds/{name}", f"lower bound {lo} is above the upper bound {hi}")
    p = mech.p()
    z0 = np.zeros(mech.n_free) if guess is None else np.asarray(guess, dtype=float)
    started = time.perf_counter()
    clipped = np.clip(z0, lower, upper)
    held = np.flatnonzero((clipped != z0)[:mech.n_body_coordinates])
    z0 = clipped
    if held.size:
        # A consistent start on the bounds: the bounded body coordinates held where the
        # bounds put them (their balance rows dropped), the rest solved by Newton.
        free = np.setdiff1d(np.arange(mech.n_free), held)

        def evaluate_held(x):
            z = z0.copy()
            z[free] = x
            R, K = mech.graphs.residual_and_tangent(z, p)
            return np.asarray(R).ravel()[free], np.asarray(K)[np.ix_(free, free)]

        status, x, _, _, _, _ = iterate(evaluate_held, z0[free], options)
        if status == "converged":
            z0[free] = x
    z_sym, p_sym = ca.SX.sym("z", mech.n_free), ca.SX.sym("p", len(p))
    R = mech.graphs.residual(z_sym, p_sym)
    solver = ca.nlpsol("bounded_equilibrium", "ipopt", {"x": z_sym, "p": p_sym, "f": 0, "g": R},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
                        "ipopt.linear_solver": "mumps", "ipopt.tol": 1e-12,
                        "ipopt.constr_viol_tol": options.tol_residual,
                        "ipopt.max_iter": max(options.max_iterations, 200)})
    solution = solver(x0=z0, p=p, lbx=lower, ubx=upper, lbg=0, ubg=0)
    z = np.asarray(solution["x"]).ravel()
    norm = float(np.abs(np.asarray(mech.graphs.residual(z, p))).max())
    # Polish inside the bounds: Newton from the IPOPT point, kept only if it stays inside.
    def evaluate(x):
        R, K = mech.graphs.residual_and_tangent(x, p)
        return np.asarray(R).ravel(), np.asarray(K)

    status, z_newton, norm_newton, _, _, _ = iterate(evaluate, z, options)
    if status == "converged" and np.all(z_newton >= lower - 1e-12) and np.all(z_newton <= upper + 1e-12):
        z, norm = z_newton, norm_newton
    iterations = int(solver.stats()["iter_count"])
    if norm <= options.tol_residual:
        return EquilibriumResult("converged", z, norm, iterations, [norm], time.perf_counter() - started, mech)
    return EquilibriumResult("not_converged", z, norm, iterations, [norm], time.perf_counter() - started, mech,
                             f"no equilibrium within the bounds: the least residual there is {norm:.3g} "
                             f"(IPOPT: {solver.stats()['return_status']})")
