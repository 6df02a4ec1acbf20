"""Design optimization: one NLP over the design variables and every load case's equilibrium,
solved by IPOPT with exact derivatives, from one or more starts.

Results are data: a status (optimal | acceptable | infeasible | not_converged | off_branch:
an optimum whose equilibrium is not the one reached by loading the mechanism), the optimum
in document units, the multipliers, IPOPT's iterations and history, and, when the problem is
infeasible, how far each constraint stays from its bounds.

Multipliers follow CasADi's sign (positive on an active upper bound, negative on a lower one),
in document units: raising an active bound by one unit changes the optimum by minus it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from flexmech.service.contact.design import run_contact_start, uses_contact
from flexmech.service.design.frequencies import disagreements, eigen_scales, response_scales
from flexmech.service.design.nlp import DesignNlp, design_nlp, least_violation, solver_for
from flexmech.service.design.problem import DesignProblem, OutputRef
from flexmech.service.design.robust_nlp import polished_tail, tail_bounds, tail_start
from flexmech.service.design.robust_report import robust_report, yield_bound
from flexmech.service.design.states import case_outputs, case_params, equilibria, output_value, polished_states
from flexmech.service.solvers.ipopt import solve

# A constraint counts as active within this (scaled) distance of its bound.
ACTIVE_TOLERANCE = 1e-7
# Least total violation (scaled constraints) above which a problem is reported infeasible.
INFEASIBLE_VIOLATION = 1e-6


@dataclass
class StartResult:
    """One IPOPT run from one start."""

    start: int
    status: str
    message: str
    ipopt_status: str
    iterations: int
    seconds: float
    x: np.ndarray  # NLP unknowns (scaled design, then every case's z)
    lam_g: np.ndarray
    lam_x: np.ndarray
    objective: float  # document units
    design: dict[str, float]  # document units
    design_start: dict[str, float]
    history: list[dict]
    equilibrium_residual: float  # nondimensional infinity norm over all cases, after polishing
    on_branch: bool  # every case's state is the one reached by loading the optimal design
    constraints: list[dict]
    multipliers: dict[str, list[float]]

    @property
    def succeeded(self) -> bool:
        return self.status in ("optimal", "acceptable")

    def summary(self) -> dict:
        return {k: v for k, v in self.__dict__.items() if k not in ("x", "lam_g", "lam_x")}


@dataclass
class OptimizationResult:
    status: str
    message: str
    best: StartResult | None
    starts: list[StartResult]
    seconds: float
    problem: DesignProblem = field(repr=False)

    def outputs(self) -> dict[str, dict[str, float]]:
        """Every output of every case at the optimum (document units)."""
        if self.best is None:
            return {}
        return case_outputs(self.problem, self.best.x)

    def summary(self) -> dict:
        best = self.best
        report = {
            "analysis": "optimize",
            "name": self.problem.mechanism.document.name,
            "status": self.status,
            "message": self.message,
            "seconds": self.seconds,
            "units": design_units(self.problem),
        }
        if best is not None:
            report.update({k: v for k, v in best.summary().items() if k not in ("status", "message", "seconds")})
            report["outputs"] = self.outputs()
            if robust := robust_report(self.problem, best.x):  # mean -+ k sigma, yields (first order)
                report["robust"] = robust
        report["starts"] = [
            {
                "start": s.start,
                "status": s.status,
                "objective": s.objective,
                "iterations": s.iterations,
                "seconds": s.seconds,
                "design": s.design,
                "design_start": s.design_start,
            }
            for s in self.starts
        ]
        return report


@dataclass
class Prepared:
    """What every start of a problem shares: the NLP, its parameters and the bounds."""

    problem: DesignProblem
    nlp: DesignNlp | None  # None: a problem over contact states
    P: np.ndarray
    objective_scale: float
    constraint_scales: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray


def design_units(problem: DesignProblem) -> dict[str, str]:
    mech = problem.mechanism
    units = {path: mech.doc_unit(mech.parameters[slot].kind) for path, slot in zip(problem.paths, problem.slots)}
    objective = problem.objective
    units["objective"] = objective.unit if objective.source == "response" else mech.doc_unit(objective.kind)
    return units


def prepare(problem: DesignProblem) -> Prepared:
    """Scales from the document's design (its equilibria), the NLP and the bounds. A problem
    that names contact results is solved over its contact states instead (service.contact.design)."""
    if uses_contact(problem):
        return Prepared(
            problem, None, np.zeros(0), 1.0, np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0)
        )
    nlp = design_nlp(problem)
    states = equilibria(problem, problem.start)
    ps = case_params(problem, problem.start)

    def typical(ref: OutputRef, *bounds: float) -> float:
        factor = problem.output_factor(ref)
        sizes = [abs(b) * factor for b in bounds if np.isfinite(b)]
        status, z = states[ref.case]
        if status == "converged":
            sizes.append(abs(output_value(problem, ref, z, ps[ref.case])))
        size = max(sizes, default=0.0)
        return size if size > 1e-12 else 1.0

    objective_scale = problem.sign * typical(problem.objective)  # negative: maximize
    constraint_scales = np.array([typical(c.output, c.lower, c.upper) for c in problem.constraints])
    P = nlp.pack(
        problem,
        objective_scale,
        constraint_scales,
        eigen_scales(problem, nlp.frequencies, states, ps),
        response_scales(problem, nlp.responses),
    )
    n_z = nlp.n_state * nlp.n_cases
    mode_lower, mode_upper = tail_bounds(nlp)  # modes, amplitudes, first-order blocks
    lbx = np.concatenate([problem.lower / problem.scale, np.full(n_z, -np.inf), mode_lower])
    ubx = np.concatenate([problem.upper / problem.scale, np.full(n_z, np.inf), mode_upper])
    factors = np.array([problem.output_factor(c.output) for c in problem.constraints])
    lower = (
        np.array([c.lower for c in problem.constraints]) * factors / constraint_scales if problem.constraints else []
    )
    upper = (
        np.array([c.upper for c in problem.constraints]) * factors / constraint_scales if problem.constraints else []
    )
    lbg = np.concatenate([np.zeros(nlp.n_residuals), lower])
    ubg = np.concatenate([np.zeros(nlp.n_residuals), upper])
    return Prepared(problem, nlp, P, objective_scale, constraint_scales, lbx, ubx, lbg, ubg)


def start_design(problem: DesignProblem, start: int) -> np.ndarray:
    """Start 0: the document's values (moved into the bounds); start k: a random point of
    the bounds (seeded by the spec's seed and k), or within half a scale where unbounded."""
    if start == 0:
        return np.clip(problem.start, problem.lower, problem.upper)
    rng = np.random.default_rng([problem.spec.seed, start])
    lo = np.where(np.isfinite(problem.lower), problem.lower, problem.start - 0.5 * problem.scale)
    hi = np.where(np.isfinite(problem.upper), problem.upper, problem.start + 0.5 * problem.scale)
    return lo + rng.random(len(lo)) * (hi - lo)


def run_start(prepared: Prepared, start: int, stop: Callable[[], bool] | None = None) -> StartResult:
    """One IPOPT run from start `start`; stop() (asked every iteration) ends it early."""
    problem, nlp = prepared.problem, prepared.nlp
    if nlp is None:
        return StartResult(**run_contact_start(problem, start, start_design(problem, start)))
    spec = problem.spec
    started = time.perf_counter()
    design0 = start_design(problem, start)
    guesses = [z if status == "converged" else np.zeros(nlp.n_state) for status, z in equilibria(problem, design0)]
    vibration0 = tail_start(problem, nlp, prepared.P, guesses, case_params(problem, design0))
    x0 = np.concatenate([design0 / problem.scale, *guesses, vibration0])
    run = solve(
        solver_for(nlp, spec.max_iterations, spec.tolerance),
        stop=stop,
        x0=x0,
        p=prepared.P,
        lbx=prepared.lbx,
        ubx=prepared.ubx,
        lbg=prepared.lbg,
        ubg=prepared.ubg,
    )
    status, x, lam_g, lam_x, message = _judged(prepared, run, x0, stop)
    # IPOPT may end a hair outside the bounds (its bound relaxation): report the design inside.
    design = np.clip(x[: nlp.n_design] * problem.scale, problem.lower, problem.upper)
    zs, on_branch = polished_states(problem, design, np.split(x[nlp.n_design : nlp.n_states], nlp.n_cases))
    residual = max(
        (
            float(np.abs(np.asarray(problem.mechanism.graphs.residual(z, p))).max(initial=0.0))
            for z, p in zip(zs, case_params(problem, design))
        ),
        default=0.0,
    )
    x = np.concatenate([design / problem.scale, *zs, polished_tail(problem, nlp, x, zs, case_params(problem, design))])
    f, _ = nlp.evaluate(x, prepared.P)
    status, message = _checked(prepared, status, message, on_branch, x, zs, design)
    return StartResult(
        start=start,
        status=status,
        message=message,
        ipopt_status=run.return_status,
        iterations=run.iterations,
        seconds=time.perf_counter() - started,
        x=x,
        lam_g=lam_g,
        lam_x=lam_x,
        objective=_objective_doc(prepared, float(f)),
        design=dict(zip(problem.paths, design.tolist())),
        design_start=dict(zip(problem.paths, design0.tolist())),
        history=_history(prepared, run.history),
        equilibrium_residual=residual,
        on_branch=on_branch,
        constraints=constraint_report(prepared, x, lam_g),
        multipliers=_multipliers(prepared, lam_g, lam_x),
    )


def _checked(prepared: Prepared, status: str, message: str, on_branch: bool, x, zs, design) -> tuple[str, str]:
    """(status, message) of a solved start after its checks: its equilibria on the branch the
    mechanism reaches, and its frequencies those of a fresh modes run."""
    if status not in ("optimal", "acceptable"):
        return status, message
    if not on_branch:
        return "off_branch", (
            "the optimum's equilibrium is not the one the mechanism reaches when loaded at that "
            "design (another branch); try other starts or tighter bounds"
        )
    problem, nlp = prepared.problem, prepared.nlp
    crossed = disagreements(problem, nlp.frequencies, x, nlp.n_states, zs, case_params(problem, design))
    return ("mode_switched", "; ".join(crossed)) if crossed else (status, message)


def _judged(prepared: Prepared, run, x0: np.ndarray, stop: Callable[[], bool] | None = None):
    """(status, x, lam_g, lam_x, message) of an IPOPT run: when it failed on a constrained
    problem, whether because no design meets the constraints (the least violation problem)."""
    problem, nlp = prepared.problem, prepared.nlp
    if run.succeeded:
        return run.status, run.x, run.lam_g, run.lam_x, ""
    if run.status == "time_limit":
        return run.status, run.x, run.lam_g, run.lam_x, "stopped: the job was cancelled or ran out of time"
    feasibility = ""
    if problem.constraints:
        x_least, violation, least_status = least_violation(
            nlp,
            x0,
            prepared.P,
            prepared.lbx,
            prepared.ubx,
            prepared.lbg,
            prepared.ubg,
            problem.spec.max_iterations,
            stop,
        )
        if least_status == "optimal" and violation > INFEASIBLE_VIOLATION:
            return (
                "infeasible",
                x_least,
                np.zeros_like(run.lam_g),
                np.zeros_like(run.lam_x),
                "no design within the bounds meets the constraints: this is the point of least violation",
            )
        if least_status == "optimal":
            feasibility = "; feasible designs exist (try other starts or more iterations)"
    if run.status == "infeasible":
        return (
            run.status,
            run.x,
            run.lam_g,
            run.lam_x,
            ("no design within the bounds meets the constraints: this is the point of least violation"),
        )
    return run.status, run.x, run.lam_g, run.lam_x, f"IPOPT: {run.return_status}{feasibility}"


def _objective_doc(prepared: Prepared, f: float) -> float:
    problem = prepared.problem
    value = f * prepared.objective_scale / problem.output_factor(problem.objective)
    return float(np.exp(value)) if problem.objective.source == "yield" else value  # the NLP holds ln(yield)


def _history(prepared: Prepared, it: dict) -> list[dict]:
    objective = it.get("obj", [])
    return [
        {
            "iteration": k,
            "objective": _objective_doc(prepared, float(objective[k])),
            "constraint_violation": float(it["inf_pr"][k]),
            "dual_infeasibility": float(it["inf_du"][k]),
        }
        for k in range(len(objective))
    ]


def _multipliers(prepared: Prepared, lam_g: np.ndarray, lam_x: np.ndarray) -> dict[str, list[float]]:
    problem, nlp = prepared.problem, prepared.nlp
    per_objective = prepared.objective_scale / problem.output_factor(problem.objective)
    constraints = [
        float(lam_g[nlp.n_residuals + k])
        * per_objective
        / (prepared.constraint_scales[k] / problem.output_factor(c.output))
        / yield_bound(c, float(lam_g[nlp.n_residuals + k]))
        for k, c in enumerate(problem.constraints)
    ]
    design = (lam_x[: nlp.n_design] * per_objective / problem.scale).tolist()
    return {"constraints": constraints, "design": design}


def constraint_report(prepared: Prepared, x: np.ndarray, lam_g: np.ndarray) -> list[dict]:
    """Each constraint's value, bounds, violation, whether active (document units; a yield as itself, not the ln the NLP holds)."""
    problem, nlp = prepared.problem, prepared.nlp
    _, g = nlp.evaluate(x, prepared.P)
    g = np.asarray(g).ravel()[nlp.n_residuals :]
    multipliers = _multipliers(prepared, lam_g, np.zeros(nlp.n_design))["constraints"]
    rows = []
    for k, c in enumerate(problem.constraints):
        value = g[k] * prepared.constraint_scales[k] / problem.output_factor(c.output)
        violation, shown = max(c.lower - value, value - c.upper, 0.0), np.exp if c.output.source == "yield" else float
        scaled_gap = min(abs(g[k] - prepared.lbg[nlp.n_residuals + k]), abs(g[k] - prepared.ubg[nlp.n_residuals + k]))
        rows.append(
            {
                "output": c.output.name,
                "case": problem.case_names[c.output.case],
                "value": float(shown(value)),
                "lower": float(shown(c.lower)) if np.isfinite(c.lower) else None,
                "upper": float(shown(c.upper)) if np.isfinite(c.upper) else None,
                "violation": float(violation),
                "active": bool(scaled_gap <= ACTIVE_TOLERANCE),
                "multiplier": float(multipliers[k]),
            }
        )
    return rows


def _best(starts: list[StartResult], sign: float) -> StartResult | None:
    good = [s for s in starts if s.succeeded]
    if good:
        return min(good, key=lambda s: sign * s.objective)
    return min(starts, key=lambda s: max((c["violation"] for c in s.constraints), default=0.0)) if starts else None


def combine(problem: DesignProblem, starts: list[StartResult], seconds: float) -> OptimizationResult:
    """The result of a set of starts: the best feasible one, else the least infeasible."""
    best = _best(starts, problem.sign)
    if best is None:
        return OptimizationResult("not_converged", "no start ran", None, starts, seconds, problem)
    if best.succeeded:
        status, message = best.status, ""
    elif all(s.status == "infeasible" for s in starts):
        worst = max(best.constraints, key=lambda c: c["violation"], default=None)
        detail = ""
        if worst is not None and worst["violation"] > 0:
            bounds = ", ".join("-" if b is None else f"{b:.6g}" for b in (worst["lower"], worst["upper"]))
            detail = (
                f"; the closest point misses {worst['output']} ({worst['case']}) by {worst['violation']:.4g} "
                f"(value {worst['value']:.6g}, bounds [{bounds}])"
            )
        status, message = "infeasible", f"no design satisfies the constraints and bounds{detail}"
    else:
        status, message = best.status, best.message
    return OptimizationResult(status, message, best, starts, seconds, problem)


def optimize(problem: DesignProblem, progress=None) -> OptimizationResult:
    """Every start of the problem in turn; progress(done, total) after each."""
    started = time.perf_counter()
    prepared = prepare(problem)
    starts = []
    for k in range(problem.spec.starts):
        starts.append(run_start(prepared, k))
        if progress is not None:
            progress(k + 1, problem.spec.starts)
    return combine(problem, starts, time.perf_counter() - started)
