"""The design NLP of a DesignProblem (simultaneous approach), as CasADi graphs.

Unknowns x = [d; z_1; ...; z_C; e_1; ...; e_F; X_1; ...; S_1; ...]: the scaled design variables
(document value / scale), the equilibrium state of every load case, for every natural frequency
the problem names its mode e = [v; l] (a right vector over z, and omega^2 / omega_0^2), every
frequency response's amplitude X, and every first-order block S of the robust outputs
(service.design.robust_nlp). Constraints g = [R(z_1, p_1); ...; R(z_C, p_C); per frequency
(K_T v - omega_0^2 l M_z v) and v.M_z v / m_0 - 1; the responses' rows; K S + R_p L per block;
outputs of the constraints / their scales]; all but the last are equalities. The objective is
(+-) its output over its scale. Every number (the cases' parameters, the design scales, the
output scales, each frequency's omega_0^2 and m_0) is an NLP parameter, so one solver serves
every start and every value; the scatter's loadings and the specs are part of the key.

A frequency's eigenpair is followed from the start's k-th mode by continuity: where modes cross
on the way, it may end as another (service.design.optimize checks the optimum by a fresh modes
run).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property, lru_cache

import casadi as ca
import numpy as np

from flexmech.models.graph.assembly import graphs_for
from flexmech.service.design.problem import DesignProblem, OutputRef
from flexmech.service.design.robust import log_yield, robust_output
from flexmech.service.design.robust_nlp import block_of, block_size, sensitivity_blocks, sensitivity_rows
from flexmech.service.solvers.ipopt import nlp_solver, solve


@dataclass(frozen=True, eq=False)
class DesignNlp:
    key: tuple
    n_design: int
    n_state: int  # per case
    n_cases: int
    n_params: int  # per case
    n_residuals: int  # rows of g that are equalities (equilibrium residuals, eigenproblems)
    frequencies: tuple[OutputRef, ...]  # the frequencies named, each with its mode among the unknowns
    responses: tuple[OutputRef, ...]  # the frequency responses named, each with its amplitude's unknowns
    sensitivities: tuple  # the (case, scatter) blocks of first-order moves the robust outputs need
    n_sensitivity: int  # their unknowns (the tail of x)
    evaluate: ca.Function  # (x, P) -> (f, g)
    x: ca.SX
    P: ca.SX
    f: ca.SX
    g: ca.SX

    @cached_property
    def kkt(self) -> ca.Function:
        """(x, P, lam_g) -> (H, L_xp, J, g_p, f_p): for sensitivities of the optimum. Built when
        first asked (an optimization never needs it: building it took 1.6 s of a start, with
        CSE, time a cancel had to wait for in one C++ call)."""
        return kkt_function(self.x, self.P, self.f, self.g)

    @property
    def n_states(self) -> int:
        """The design variables' and the cases' states' share of x (the modes follow)."""
        return self.n_design + self.n_state * self.n_cases

    def pack(
        self,
        problem: DesignProblem,
        objective_scale: float,
        constraint_scales: np.ndarray,
        eigen_scales: np.ndarray = np.zeros(0),
        response_scales: np.ndarray = np.zeros(0),
    ) -> np.ndarray:
        """The NLP parameter vector: every case's parameters, the design scales (nondim per
        scaled unit), the objective's scale (negative to maximize), the constraints' scales
        (nondimensional) and each frequency's (omega_0^2, m_0)."""
        design_scale = problem.scale * problem.nd_per_doc
        return np.concatenate(
            [*problem.case_p, design_scale, [objective_scale], constraint_scales, eigen_scales, response_scales]
        )


def _key(problem: DesignProblem) -> tuple:
    refs = (problem.objective, *(c.output for c in problem.constraints))
    return (problem.mechanism.structure, problem.slots, len(problem.case_p), refs)


def design_nlp(problem: DesignProblem) -> DesignNlp:
    """The NLP graphs of a problem's structure, built once per process (numbers are parameters)."""
    return _design_nlp(_key(problem))


@lru_cache(maxsize=16)
def _design_nlp(key: tuple) -> DesignNlp:
    structure, slots, n_cases, refs = key
    graphs = graphs_for(structure)
    n_state, n_params, n_design = structure.n_unknowns, len(structure.parameters), len(slots)
    frequencies = tuple(dict.fromkeys(ref for ref in refs if ref.source == "frequency"))
    responses = tuple(dict.fromkeys(ref for ref in refs if ref.source == "response"))
    d = ca.SX.sym("d", n_design)
    zs = [ca.SX.sym(f"z{c}", n_state) for c in range(n_cases)]
    modes = [ca.SX.sym(f"mode{j}", n_state + 1) for j in range(len(frequencies))]
    amplitudes = [ca.SX.sym(f"response{j}", 2 * n_state) for j in range(len(responses))]
    blocks = sensitivity_blocks(refs)
    n_fixed = n_params * n_cases + n_design + 1 + len(refs) - 1
    n_eigen = 2 * len(frequencies)
    P = ca.SX.sym("P", n_fixed + n_eigen + (len(responses) + 2 if responses else 0))
    design_scale = P[n_params * n_cases : n_params * n_cases + n_design]
    objective_scale = P[n_params * n_cases + n_design]
    constraint_scales = P[n_params * n_cases + n_design + 1 : n_fixed]
    ps = []
    for c in range(n_cases):
        pc = P[c * n_params : (c + 1) * n_params]
        for k, slot in enumerate(slots):
            pc[slot] = d[k] * design_scale[k]
        ps.append(pc)
    residuals = [graphs.residual(zs[c], ps[c]) for c in range(n_cases)]
    eigen_rows, omegas = _eigenproblems(structure, frequencies, zs, ps, modes, P[n_fixed : n_fixed + n_eigen])
    response_rows, magnitudes = _responses(structure, responses, zs, ps, amplitudes, P[n_fixed + n_eigen :])
    sensitivities, sensitivity_eqs, firsts = sensitivity_rows(structure, blocks, zs, ps)
    outputs: dict[int, ca.SX] = {}

    def value(ref: OutputRef) -> ca.SX:
        c = ref.case
        if ref.source == "yield":
            return log_yield(*firsts[block_of(ref)], ref.robust.specs)
        if ref.sigmas:
            return robust_output(*firsts[block_of(ref)], ref.index, ref.sigmas)
        if ref.source == "frequency":
            return omegas[frequencies.index(ref)] / (2 * np.pi)
        if ref.source == "response":
            return magnitudes[responses.index(ref)]
        if ref.source == "parameter":
            return ps[c][ref.index]
        if ref.source == "stiffness":
            K = graphs.residual_and_tangent(zs[c], ps[c])[1]
            unit = ca.DM.zeros(n_state)
            unit[ref.index] = 1
            return 1 / ca.solve(K, unit)[ref.index]  # 1 / compliance: the condensed diagonal
        if c not in outputs:
            outputs[c] = graphs.outputs(zs[c], ps[c])
        return outputs[c][ref.index]

    f = value(refs[0]) / objective_scale
    constraint_rows = [value(ref) / constraint_scales[k] for k, ref in enumerate(refs[1:])]
    x = ca.vertcat(d, *zs, *modes, *amplitudes, *sensitivities)
    g = ca.vertcat(*residuals, *eigen_rows, *response_rows, *sensitivity_eqs, *constraint_rows)
    evaluate = _no_free_symbols(ca.Function("design_nlp", [x, P], [f, g], ["x", "P"], ["f", "g"], dict(cse=True)))
    n_sensitivity = sum(block_size(structure, block) for block in blocks)
    n_equalities = n_state * n_cases + (n_state + 1) * len(frequencies) + 2 * n_state * len(responses) + n_sensitivity
    counts = (n_design, n_state, n_cases, n_params, n_equalities)
    return DesignNlp(key, *counts, frequencies, responses, blocks, n_sensitivity, evaluate, x, P, f, g)


def kkt_function(x: ca.SX, P: ca.SX, f: ca.SX, g: ca.SX) -> ca.Function:
    """The KKT terms (x, P, lam_g) -> (H, L_xp, J, g_p, f_p) for sensitivities of an optimum:
    without CSE, which took seconds to build for a Function evaluated once per analysis."""
    lam = ca.SX.sym("lam_g", g.shape[0])
    gradient = ca.gradient(f + ca.dot(lam, g), x)
    kkt = ca.Function(
        "design_kkt",
        [x, P, lam],
        [ca.jacobian(gradient, x), ca.jacobian(gradient, P), ca.jacobian(g, x), ca.jacobian(g, P), ca.gradient(f, P)],
        ["x", "P", "lam_g"],
        ["H", "L_xp", "J", "g_p", "f_p"],
    )
    return _no_free_symbols(kkt)


def _no_free_symbols(fn: ca.Function) -> ca.Function:
    if fn.has_free():
        raise RuntimeError(f"graph {fn.name()} has free symbols {fn.get_free()}")
    return fn


def _responses(structure, responses, zs, ps, amplitudes, scales) -> tuple[list[ca.SX], list[ca.SX]]:
    """Per response: the rows of (K_T - omega^2 M + i omega D) X = f in real and imaginary parts,
    D = alpha M + beta K_T, f the load's unit force (R is affine in a load); and |dy/dz . X| in
    document units (scales: a factor per response, then alpha and beta)."""
    if not responses:
        return [], []
    from flexmech.models.graph.modal import state_mass

    graphs, mass = graphs_for(structure), state_mass(structure)
    alpha, beta = scales[len(responses)], scales[len(responses) + 1]
    rows, magnitudes = [], []
    for j, ref in enumerate(responses):
        z, p = zs[ref.case], ps[ref.case]
        n = z.numel()
        real, imaginary = amplitudes[j][:n], amplitudes[j][n:]
        omega = 2 * np.pi * ref.frequency
        R = graphs.residual(z, p)
        pushed = ca.SX(p)
        pushed[ref.input] = p[ref.input] + 1
        force = R - graphs.residual(z, pushed)
        M = mass(z, p)

        def stiff(v: ca.SX) -> ca.SX:
            return ca.jtimes(R, z, v)

        def damped(v: ca.SX) -> ca.SX:
            return alpha * ca.mtimes(M, v) + beta * stiff(v)

        rows += [stiff(real) - omega**2 * ca.mtimes(M, real) - omega * damped(imaginary) - force]
        rows += [stiff(imaginary) - omega**2 * ca.mtimes(M, imaginary) + omega * damped(real)]
        y = graphs.outputs(z, p)[ref.index]
        magnitudes.append(scales[j] * ca.sqrt(ca.jtimes(y, z, real) ** 2 + ca.jtimes(y, z, imaginary) ** 2))
    return rows, magnitudes


def _eigenproblems(structure, frequencies, zs, ps, modes, scales) -> tuple[list[ca.SX], list[ca.SX]]:
    """Per frequency: its eigenproblem's rows and omega (rad/s), from its mode's unknowns."""
    if not frequencies:
        return [], []
    from flexmech.models.graph.modal import state_mass

    graphs, mass = graphs_for(structure), state_mass(structure)
    rows, omegas = [], []
    for j, ref in enumerate(frequencies):
        v, share = modes[j][:-1], modes[j][-1]
        omega_squared = scales[2 * j] * share
        z, p = zs[ref.case], ps[ref.case]
        M = mass(z, p)
        rows += [ca.jtimes(graphs.residual(z, p), z, v) - omega_squared * ca.mtimes(M, v)]
        rows += [ca.dot(v, ca.mtimes(M, v)) / scales[2 * j + 1] - 1]
        omegas.append(ca.sqrt(omega_squared))
    return rows, omegas


def solver_for(nlp: DesignNlp, max_iterations: int, tolerance: float) -> ca.Function:
    """IPOPT on the design NLP (exact Hessian of the Lagrangian), one per setting."""
    return nlp_solver(
        "design",
        nlp.key,
        lambda: {"x": nlp.x, "p": nlp.P, "f": nlp.f, "g": nlp.g},
        {"tol": tolerance, "max_iter": max_iterations, "mu_strategy": "adaptive"},
    )


def _elastic_solver(nlp: DesignNlp, max_iterations: int) -> ca.Function:
    def problem() -> dict:
        n_con = nlp.g.shape[0] - nlp.n_residuals
        slack = ca.SX.sym("s", n_con)
        residuals, constraints = nlp.g[: nlp.n_residuals], nlp.g[nlp.n_residuals :]
        return {
            "x": ca.vertcat(nlp.x, slack),
            "p": nlp.P,
            "f": ca.sum1(slack),
            "g": ca.vertcat(residuals, constraints - slack, constraints + slack),
        }

    return nlp_solver("design_feasibility", nlp.key, problem, {"tol": 1e-10, "max_iter": max_iterations})


def least_violation(
    nlp: DesignNlp,
    x0: np.ndarray,
    P: np.ndarray,
    lbx: np.ndarray,
    ubx: np.ndarray,
    lbg: np.ndarray,
    ubg: np.ndarray,
    max_iterations: int,
    stop: Callable[[], bool] | None = None,
) -> tuple[np.ndarray, float, str]:
    """The point of least total constraint violation (in scaled units) with every case in
    equilibrium and the design within its bounds: minimize the sum of elastic slacks s >= 0
    with lower - s <= g <= upper + s. Returns (x, total violation, IPOPT status)."""
    solver = _elastic_solver(nlp, max_iterations)
    n_res = nlp.n_residuals
    lower, upper = lbg[n_res:], ubg[n_res:]
    _, g = nlp.evaluate(x0, P)
    g = np.asarray(g).ravel()[n_res:]
    s0 = np.maximum(np.maximum(lower - g, g - upper), 0.0) + 1e-3
    n_con = len(lower)
    outcome = solve(
        solver,
        stop=stop,
        x0=np.concatenate([x0, s0]),
        p=P,
        lbx=np.concatenate([lbx, np.zeros(n_con)]),
        ubx=np.concatenate([ubx, np.full(n_con, np.inf)]),
        lbg=np.concatenate([np.zeros(n_res), np.full(n_con, -np.inf), lower]),
        ubg=np.concatenate([np.zeros(n_res), upper, np.full(n_con, np.inf)]),
    )
    x = outcome.x
    return x[: len(x0)], float(np.sum(x[len(x0) :])), outcome.status
