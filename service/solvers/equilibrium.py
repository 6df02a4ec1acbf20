"""The equilibrium of a mechanism: Newton's method on R(z, p) = 0 with the exact tangent
stiffness (service.solvers.newton), and within bounds on the unknowns with IPOPT.

The paper's update strategies are options: the full K_T or its first term K_T^I only, or
K_T frozen at one state (Fig. 11). Non-convergence is a status in the result, never an
exception.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import lru_cache

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.graph.assembly import graphs_for
from flexmech.models.graph.residual import unknown_names as element_unknowns
from flexmech.service.buffered import BufferedCall
from flexmech.service.solvers import ipopt
from flexmech.service.solvers.newton import (  # noqa: F401 (NewtonOptions, Status: re-exported)
    NewtonOptions,
    Status,
    dense_solve,
    iterate,
    iterate_dense,
    sparse_direction,
    sparse_step,
)
from flexmech.service.units import displacement_to_doc, outputs_in_doc_units, residual_report

# Seed 000, Sec. 2: the constant-stiffness curved beam is faithful up to about +-20 deg.
ROTATION_VALIDITY_DEG = 20.0


@dataclass
class EquilibriumResult:
    status: Status
    z: np.ndarray  # free displacements, nondimensional
    solver_residual: float  # nondimensional infinity norm of every row of R (Newton's test)
    iterations: int
    history: list[float]  # residual norm before each iteration
    seconds: float
    mechanism: Mechanism = field(repr=False)
    message: str = ""

    @property
    def converged(self) -> bool:
        return self.status == "converged"

    def residuals(self) -> dict:
        """service.units.residual_report of this state."""
        return residual_report(self.mechanism, self.z)

    @property
    def residual_norm_force(self) -> float:
        """Largest unbalanced force, in the document's force unit."""
        return self.residuals()["residual_norm"]

    @property
    def residual_norm_moment(self) -> float:
        """Largest unbalanced moment, in the document's moment unit."""
        return self.residuals()["residual_moment"]

    def outputs(self) -> dict[str, float]:
        """Every named scalar (poses, reactions, flexure wrenches and stresses, points) in
        document units."""
        m = self.mechanism
        return outputs_in_doc_units(m, m.graphs.outputs(self.z, m.p()))

    def warnings(self, outputs: dict[str, float] | None = None) -> list[str]:
        """Where the result leaves the range its models are known to hold in (`outputs`: this
        result's outputs() when already at hand)."""
        m = self.mechanism
        notes = list(m.notes)
        rad_per_unit = m.doc_factor("angle")
        for name, value in (outputs if outputs is not None else self.outputs()).items():
            if name.startswith("elements.") and name.endswith(".rotation"):
                degrees = abs(value) * rad_per_unit * 180 / np.pi
                if degrees > ROTATION_VALIDITY_DEG:
                    element = name.split(".")[1]
                    notes.append(
                        f"flexure {element} rotates {degrees:.1f} deg: the constant-stiffness "
                        f"curved-beam models hold to about {ROTATION_VALIDITY_DEG:.0f} deg (Cammarata et al. 2022)"
                    )
        return notes

    def displacements(self) -> dict[str, float]:
        return dict(zip(self.mechanism.free_coordinates, displacement_to_doc(self.mechanism, self.z)))

    def summary(self) -> dict:
        outputs = self.outputs()
        return {**self.summary_of_state(outputs), "displacements": self.displacements(), "outputs": outputs}

    def summary_of_state(self, outputs: dict | None = None) -> dict:
        """The status, residual and warnings, without the displacements and outputs."""
        if outputs is None and self.converged:
            outputs = self.outputs()
        return {
            "status": self.status,
            "message": self.message,
            "iterations": self.iterations,
            **residual_report(self.mechanism, self.z),
            "seconds": self.seconds,
            "warnings": self.warnings(outputs) if self.converged else [],
        }


_CHECKED: set[str] = set()  # structures whose undeformed stiffness was found regular


def check_constrained(mech: Mechanism, p: np.ndarray | None = None, again: bool = False) -> None:
    """Raise MechanismError if K_T is singular in the undeformed state (a free motion that no
    element resists), naming the coordinates that move in the mechanism's free motion. Done
    once per structure (a dense SVD), and again (`again`) when a solve meets a singular K."""
    if mech.n_free == 0 or (mech.structure.key in _CHECKED and not again):
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
        if moving:
            raise MechanismError(
                "/bodies",
                "under-constrained: the tangent stiffness is singular in the undeformed state; "
                f"nothing resists a motion of {', '.join(moving)} (connect those bodies with flexures or fix them)",
            )
        # no body moves: the singular direction is in the elements' own unknowns, forces that
        # nothing determines (two inextensible links that hold the same distance, say)
        undetermined = [
            name
            for (name, _), a in zip(element_unknowns(mech.structure), amplitude)
            if a > 1e-6 and name not in mech.free_coordinates
        ]
        shown = ", ".join(undetermined[:8]) + (f" and {len(undetermined) - 8} more" if len(undetermined) > 8 else "")
        raise MechanismError(
            "/elements",
            "the tangent stiffness is singular in the undeformed state, though every body is held: the elements' "
            f"unknowns {shown} are not determined (redundant constraints: for example inextensible links that "
            "fix the same distance; give one of them axial strain or remove it)",
        )
    _CHECKED.add(mech.structure.key)


@lru_cache(maxsize=16)
def _newton_step(structure) -> ca.Function:
    return sparse_step(graphs_for(structure).residual_and_tangent)


def newton(
    mech: Mechanism, p: np.ndarray, z0: np.ndarray, options: NewtonOptions, frozen_tangent: np.ndarray | None = None
) -> EquilibriumResult:
    """Newton from z0 with the matrix options.jacobian chooses: the full K_T (factored
    sparsely), its first term K_T^I, or K_T frozen (at the undeformed state by default)."""
    g = mech.graphs
    started = time.perf_counter()
    evaluate = BufferedCall(g.residual) if mech.n_free else None  # 15 us a call instead of 80

    def residual(z):
        return evaluate(z, p)[0].ravel() if evaluate is not None else np.asarray(g.residual(z, p)).ravel()

    if options.jacobian == "full" and mech.n_free:
        direction = sparse_direction(_newton_step(mech.structure.unnamed), p)
    elif options.jacobian == "first_term":

        def direction(z, R):
            return dense_solve(np.asarray(g.tangent_terms(z, p)[0]), R)
    else:
        if frozen_tangent is None:
            frozen_tangent = np.asarray(g.residual_and_tangent(np.zeros(mech.n_free), p)[1])

        def direction(z, R):
            return dense_solve(frozen_tangent, R)

    status, z, norm, k, history, message = iterate(residual, direction, z0, options)
    return EquilibriumResult(status, z, norm, k, history, time.perf_counter() - started, mech, message)


def solve_equilibrium(
    mech: Mechanism,
    options: NewtonOptions = NewtonOptions(),
    guess: np.ndarray | None = None,
    frozen_tangent: np.ndarray | None = None,
    check: bool = True,
) -> EquilibriumResult:
    """Equilibrium of `mech` under its loads. `guess`: nondimensional free displacements
    (default: the undeformed state)."""
    p = mech.p()
    if check:
        check_constrained(mech, p)
    z0 = np.zeros(mech.n_free) if guess is None else np.asarray(guess, dtype=float)
    if z0.shape != (mech.n_free,):
        raise ValueError(f"guess: expected {mech.n_free} values, got {z0.shape}")
    result = newton(mech, p, z0, options, frozen_tangent)
    if check and result.status == "singular":
        check_constrained(mech, p, again=True)
    return result


def unknown_names(mech: Mechanism) -> list[str]:
    """A name for every entry of z: the free body coordinates ("tip.x"), then each element's
    own unknowns, e.g. per link its internal force, start rotation and start moment ("L1.h",
    "L1.v", "L1.rotation_start", "L1.M_start") and its inner shooting states ("L1.node3.psi")."""
    return [name for name, _ in element_unknowns(mech.structure)]


def solve_bounded(
    mech: Mechanism,
    bounds: dict[str, tuple[float | None, float | None]],
    options: NewtonOptions = NewtonOptions(),
    guess: np.ndarray | None = None,
) -> EquilibriumResult:
    """Equilibrium with bounds on unknowns (Lan 2005 Sec. 2.2.2, bounded Gauss-Newton): find
    R(z) = 0 inside the bounds with IPOPT and exact derivatives (a feasibility problem: the
    residuals are equality constraints; IPOPT's restoration phase reports an empty set).
    Bounds are in document units (angles: the document's angle unit), keyed by
    unknown_names(); None: unbounded. Where several equilibria exist (a buckled column), the
    bounds pick the branch whose basin holds the start on the bounds."""
    lower, upper = _bounds(mech, bounds)
    p = mech.p()
    started = time.perf_counter()
    z0 = _start_on_bounds(
        mech, p, np.zeros(mech.n_free) if guess is None else np.asarray(guess, dtype=float), lower, upper, options
    )
    run = ipopt.solve(
        _bounded_solver(mech.structure, options),
        stop=ipopt.deadline(options.time_limit),
        x0=z0,
        p=p,
        lbx=lower,
        ubx=upper,
        lbg=0,
        ubg=0,
    )
    z = run.x
    norm = float(np.abs(np.asarray(mech.graphs.residual(z, p))).max())
    # Polish inside the bounds: Newton from the IPOPT point, kept only if it stays inside.
    polished = newton(mech, p, z, options)
    status, z_newton, norm_newton = polished.status, polished.z, polished.solver_residual
    if status == "converged" and np.all(z_newton >= lower - 1e-12) and np.all(z_newton <= upper + 1e-12):
        z, norm = z_newton, norm_newton
    seconds = time.perf_counter() - started
    if norm <= options.tol_residual:
        return EquilibriumResult("converged", z, norm, run.iterations, [norm], seconds, mech)
    return EquilibriumResult(
        "not_converged",
        z,
        norm,
        run.iterations,
        [norm],
        seconds,
        mech,
        f"no equilibrium within the bounds: the least residual there is {norm:.3g} (IPOPT: {run.return_status})",
    )


def _bounds(mech: Mechanism, bounds: dict) -> tuple[np.ndarray, np.ndarray]:
    """Nondimensional lower and upper bounds of z from bounds in document units, by name."""
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
    return lower, upper


def _start_on_bounds(mech: Mechanism, p: np.ndarray, z0: np.ndarray, lower, upper, options) -> np.ndarray:
    """A consistent start on the bounds: the bounded body coordinates held where the bounds
    put them (their balance rows dropped), the rest solved by Newton."""
    clipped = np.clip(z0, lower, upper)
    held = np.flatnonzero((clipped != z0)[: mech.n_body_coordinates])
    z0 = clipped
    if held.size:
        free = np.setdiff1d(np.arange(mech.n_free), held)

        def evaluate_held(x):
            z = z0.copy()
            z[free] = x
            R, K = mech.graphs.residual_and_tangent(z, p)
            return np.asarray(R).ravel()[free], np.asarray(K)[np.ix_(free, free)]

        status, x, _, _, _, _ = iterate_dense(evaluate_held, z0[free], options)
        if status == "converged":
            z0[free] = x
    return z0


def _bounded_solver(structure, options: NewtonOptions):
    """IPOPT on R(z) = 0 within bounds (a feasibility problem), built once per structure."""

    def problem() -> dict:
        import casadi as ca

        z, p = ca.SX.sym("z", structure.n_unknowns), ca.SX.sym("p", len(structure.parameters))
        return {"x": z, "p": p, "f": 0, "g": graphs_for(structure).residual(z, p)}

    return ipopt.nlp_solver(
        "bounded_equilibrium",
        structure,
        problem,
        {"tol": 1e-12, "constr_viol_tol": options.tol_residual, "max_iter": max(options.max_iterations, 200)},
    )
