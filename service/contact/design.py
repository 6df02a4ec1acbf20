"""Design optimization with contact: an objective or a constraint that names a contact
result (contacts.<pair>.force_x, ...) makes every evaluation a contact state (each load
case's, warm-started from its last), and the gradients its exact sensitivities on the active
set (service.contact.sensitivity). The reduced problem over the design variables is solved
by SLSQP with those gradients (its multipliers are not reported). Contact states in a design
problem are frictionless (friction needs a path to know its direction)."""

from __future__ import annotations

import time

import numpy as np
from scipy.optimize import minimize

from flexmech.service.contact.kkt import split
from flexmech.service.contact.problem import contact_problem
from flexmech.service.contact.report import friction_coefficients
from flexmech.service.contact.sensitivity import contact_sensitivities
from flexmech.service.contact.solve import ContactState, PenetratingStart, solve_state
from flexmech.service.design.problem import DesignProblem, OutputRef

CONTACT_SOURCE = "contact"


def uses_contact(problem: DesignProblem) -> bool:
    refs = [problem.objective, *[c.output for c in problem.constraints]]
    return any(ref.source == CONTACT_SOURCE for ref in refs)


class ContactEvaluator:
    """Values and gradients (document units) of the problem's outputs at a design, one
    contact state per case, each from the case's previous state."""

    def __init__(self, problem: DesignProblem):
        self.problem = problem
        self.mech = problem.mechanism
        self.contact = contact_problem(self.mech.structure)
        self.states: list[ContactState | None] = [None] * len(problem.case_p)
        self._at: np.ndarray | None = None
        self._values: dict = {}

    def evaluate(self, design: np.ndarray) -> dict:
        """{(name, case): (value, gradient over the design variables)}, or raises RuntimeError
        when a case's contact state does not converge."""
        if self._at is not None and np.array_equal(design, self._at):
            return self._values
        refs = [self.problem.objective, *[c.output for c in self.problem.constraints]]
        out = {}
        for case, p_case in enumerate(self.problem.case_p):
            p = p_case.copy()
            p[list(self.problem.slots)] = design * self.problem.nd_per_doc
            state = solve_state(
                self.contact, p, 0 * friction_coefficients(self.mech, self.contact, p), self.states[case]
            )
            if not state.converged:
                raise RuntimeError(
                    f"case {self.problem.case_names[case]}: the contact state did not converge ({state.message})"
                )
            self.states[case] = state
            names = sorted({ref.name for ref in refs if ref.case == case and ref.source != "parameter"})
            found, _ = (
                contact_sensitivities(self.mech, self.contact, state, list(self.problem.paths), names)
                if names
                else (None, [])
            )
            y = np.asarray(
                self.contact.outputs(state.v, p, state.mode.phi, state.mode.stick, state.mode.weights), dtype=float
            ).ravel()
            for k, name in enumerate(names):
                index = self.contact.output_names.index(name)
                value = y[index] / self.mech.nd_per_doc(self.contact.output_kinds[index])
                out[(name, case)] = (value, found.matrix[k])
            for ref in refs:
                if ref.case == case and ref.source == "parameter":
                    out[(ref.name, case)] = (
                        self.mech.value(ref.name)
                        if ref.name not in self.problem.paths
                        else float(design[self.problem.paths.index(ref.name)]),
                        np.array([1.0 if path == ref.name else 0.0 for path in self.problem.paths]),
                    )
        self._at, self._values = design.copy(), out
        return out

    def value(self, ref: OutputRef, design: np.ndarray) -> tuple[float, np.ndarray]:
        return self.evaluate(design)[(ref.name, ref.case)]


def run_contact_start(problem: DesignProblem, start: int, design0: np.ndarray) -> dict:
    """One start (from design0, document units) of a design problem with contact outputs:
    the fields of a service.design.optimize.StartResult."""
    started = time.perf_counter()
    evaluator = ContactEvaluator(problem)
    scale, sign = problem.scale, problem.sign
    try:
        objective_size = max(abs(evaluator.value(problem.objective, design0)[0]), 1e-12)
    except (RuntimeError, PenetratingStart) as exc:
        return _failed(problem, start, design0, str(exc), started)

    def objective(y):
        value, gradient = evaluator.value(problem.objective, y * scale)
        return sign * value / objective_size, sign * gradient * scale / objective_size

    constraints, bounds = _scaled_constraints(problem, evaluator), _scaled_bounds(problem)
    try:
        run = minimize(
            objective,
            design0 / scale,
            jac=True,
            bounds=bounds,
            constraints=constraints,
            method="SLSQP",
            options={"maxiter": problem.spec.max_iterations, "ftol": problem.spec.tolerance},
        )
    except (RuntimeError, PenetratingStart) as exc:
        return _failed(problem, start, design0, str(exc), started)
    design = np.clip(run.x * scale, problem.lower, problem.upper)
    rows = _constraint_rows(problem, evaluator, design)
    feasible = all(row["violation"] <= 1e-6 * max(1.0, abs(row["value"])) for row in rows)
    status = "optimal" if run.success and feasible else ("infeasible" if not feasible else "not_converged")
    return _start(
        start,
        status,
        "" if status == "optimal" else str(run.message),
        f"SLSQP: {run.message}",
        int(run.nit),
        time.perf_counter() - started,
        _state_vector(problem, evaluator, design),
        evaluator.value(problem.objective, design)[0],
        problem,
        design,
        design0,
        max((s.kkt_norm for s in evaluator.states if s is not None), default=0.0),
        rows,
    )


def _scaled_constraints(problem: DesignProblem, evaluator: ContactEvaluator) -> list[dict]:
    """SLSQP's constraints over the scaled design y (design / scale): each finite bound of an
    output, relative to the bound's size (an equality once)."""
    scale = problem.scale
    constraints = []
    for c in problem.constraints:
        for bound, direction in ((c.lower, 1.0), (c.upper, -1.0)):
            if np.isfinite(bound):
                kind = "eq" if c.lower == c.upper else "ineq"
                size = max(abs(bound), 1e-12)
                constraints.append(
                    {
                        "type": kind,
                        "fun": lambda y, c=c, b=bound, d=direction, s=size: (
                            d * (evaluator.value(c.output, y * scale)[0] - b) / s
                        ),
                        "jac": lambda y, c=c, d=direction, s=size: (
                            d * evaluator.value(c.output, y * scale)[1] * scale / s
                        ),
                    }
                )
                if kind == "eq":
                    break
    return constraints


def _scaled_bounds(problem: DesignProblem) -> list[tuple[float | None, float | None]]:
    """SLSQP's bounds on the scaled design (None: unbounded)."""
    bounds = list(zip(problem.lower / problem.scale, problem.upper / problem.scale))
    return [(None if not np.isfinite(lo) else lo, None if not np.isfinite(hi) else hi) for lo, hi in bounds]


def _constraint_rows(problem, evaluator, design) -> list[dict]:
    rows = []
    for c in problem.constraints:
        value = evaluator.value(c.output, design)[0]
        violation = max(c.lower - value, value - c.upper, 0.0)
        active = any(np.isfinite(b) and abs(value - b) <= 1e-7 * max(1.0, abs(b)) for b in (c.lower, c.upper))
        rows.append(
            {
                "output": c.output.name,
                "case": problem.case_names[c.output.case],
                "value": value,
                "lower": c.lower if np.isfinite(c.lower) else None,
                "upper": c.upper if np.isfinite(c.upper) else None,
                "violation": violation,
                "active": active,
                "multiplier": None,
            }
        )
    return rows


def _state_vector(problem, evaluator, design) -> np.ndarray:
    """[design / scale, every case's residual-form z at its contact state] (as the
    simultaneous optimizer stores its optimum)."""
    zs = []
    for state in evaluator.states:
        parts = split(evaluator.contact, state.v)
        zs.append(evaluator.contact.to_state(parts.w, parts.lam_eq))
    return np.concatenate([design / problem.scale, *zs])


def _failed(problem, start, design0, message, started) -> dict:
    return _start(
        start,
        "not_converged",
        message,
        "",
        0,
        time.perf_counter() - started,
        design0 / problem.scale,
        float("nan"),
        problem,
        design0,
        design0,
        float("nan"),
        [],
    )


def _start(
    start, status, message, solver_status, iterations, seconds, x, objective, problem, design, design0, residual, rows
) -> dict:
    return {
        "start": start,
        "status": status,
        "message": message,
        "ipopt_status": solver_status,
        "iterations": iterations,
        "seconds": seconds,
        "x": x,
        "lam_g": np.zeros(0),
        "lam_x": np.zeros(0),
        "objective": objective,
        "design": dict(zip(problem.paths, np.asarray(design).tolist())),
        "design_start": dict(zip(problem.paths, np.asarray(design0).tolist())),
        "history": [],
        "equilibrium_residual": residual,
        "on_branch": True,
        "constraints": rows,
        "multipliers": {"constraints": [None] * len(rows), "design": [None] * len(problem.paths)},
    }
