"""The equilibrium as the minimum of the total potential (the energy form), by IPOPT.

    minimize V(x, p)  subject to  g(x, p) = 0,  h(x, p) >= 0

x the free body coordinates; the equalities' multipliers are the joints' unknowns, so the
result is a state z = [x; lam] of the residual form, and everything /v1/solve reports (outputs,
reactions, stiffness) follows from it. A structure with an element whose model has no energy
form (constant-stiffness curved beams, shooting links) is refused, naming the element.
"""

from __future__ import annotations

import time

import numpy as np

from flexmech.models import Mechanism
from flexmech.service.solvers import ipopt
from flexmech.service.solvers.equilibrium import EquilibriumResult
from flexmech.service.solvers.newton import NewtonOptions


def _solver(mech: Mechanism, options: NewtonOptions):
    form = mech.graphs.energy_form

    def problem() -> dict:
        import casadi as ca

        x = ca.SX.sym("x", len(form.unknowns))
        p = ca.SX.sym("p", len(mech.parameters))
        return {
            "x": x,
            "p": p,
            "f": form.potential(x, p),
            "g": ca.vertcat(form.equalities(x, p), form.inequalities(x, p)),
        }

    return form, ipopt.nlp_solver(
        "minimum_energy",
        mech.structure,
        problem,
        {"tol": 1e-14, "constr_viol_tol": 1e-14, "acceptable_tol": 1e-10, "max_iter": max(options.max_iterations, 200)},
    )


def minimize_energy(
    mech: Mechanism,
    options: NewtonOptions = NewtonOptions(),
    guess: np.ndarray | None = None,
    p: np.ndarray | None = None,
) -> EquilibriumResult:
    """The minimum of the total potential from `guess` (the energy form's x, nondimensional;
    default the undeformed state) at the parameters p (default the mechanism's). Its
    solver_residual is that of the residual form there."""
    started = time.perf_counter()
    if mech.n_free == 0:  # nothing moves: the undeformed state is the whole answer
        return EquilibriumResult("converged", np.zeros(0), 0.0, 0, [], time.perf_counter() - started, mech)
    form, solver = _solver(mech, options)
    p = mech.p() if p is None else p
    n_eq, n_in = len(form.equality_names), len(form.inequality_names)
    x0 = np.zeros(len(form.unknowns)) if guess is None else np.asarray(guess, dtype=float)
    run = ipopt.solve(
        solver,
        stop=ipopt.deadline(options.time_limit),
        x0=x0,
        p=p,
        lbg=np.zeros(n_eq + n_in),
        ubg=np.concatenate([np.zeros(n_eq), np.full(n_in, np.inf)]),
    )
    z = form.to_state(run.x, run.lam_g[:n_eq])
    norm = float(np.abs(np.asarray(mech.graphs.residual(z, p))).max(initial=0.0))
    status = {"optimal": "converged", "acceptable": "converged", "time_limit": "time_limit"}.get(
        run.status, "not_converged"
    )
    if run.return_status == "Search_Direction_Becomes_Too_Small" and norm <= options.tol_residual:
        status = "converged"  # IPOPT stopped at rounding level: the residual form says so
    message = "" if status == "converged" else f"IPOPT: {run.return_status}"
    history = [float(v) for v in run.history.get("inf_du", [])]
    return EquilibriumResult(status, z, norm, run.iterations, history, time.perf_counter() - started, mech, message)
