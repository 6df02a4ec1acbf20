"""One contact state: the minimum of the total potential under non-penetration by IPOPT
(warm-started from the previous state of a path, or approached from a penetrating start),
polished by Newton on the active-set KKT system, then friction.

Friction, consistently: at a slipping pair the tangential force mu F_n acts on the site,
opposing the site's slide relative to the object over the step from the reference (previous)
state, and the shape is in equilibrium with it; a pair whose slide would run with its
friction force sticks instead (its contact point moves with the object; the tangential
force is whatever holds it, up to mu F_n). The slide comes from the previous state of a
path, or, for a single state, from the rate at which a given motion of the parameters moves
the contact (the state's own sensitivity); with neither, the state is frictionless.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from flexmech.service.contact.kkt import CONSISTENCY, Mode, consistent_active_set, split
from flexmech.service.contact.problem import ContactProblem
from flexmech.service.solvers import ipopt

IPOPT_OPTIONS = {"tol": 1e-12, "constr_viol_tol": 1e-12, "acceptable_tol": 1e-9, "max_iter": 500}
WARM = {
    "warm_start_init_point": "yes",
    "warm_start_bound_push": 1e-9,
    "warm_start_mult_bound_push": 1e-9,
    "warm_start_slack_bound_push": 1e-9,
    "mu_init": 1e-6,
}
APPROACH_STEP = 0.02  # largest fall of the relaxation per approach step (nondimensional length)
SEPARATION_DIRECTIONS = 180  # directions tried for the line of least overlap before narrowing down
FRICTION_ROUNDS = 8


class PenetratingStart(Exception):
    """The start state penetrates an object (and the caller asked not to approach it)."""

    def __init__(self, pair: int, depth: float):
        self.pair, self.depth = pair, depth
        super().__init__(f"pair {pair} penetrates by {depth:g}")

    def __reduce__(self):  # pickled with its fields, so it crosses from a worker process whole
        return (PenetratingStart, (self.pair, self.depth))


@dataclass(frozen=True)
class ContactOptions:
    penetrating_start: str = "approach"  # approach | refuse
    time_limit: float | None = None


@dataclass
class ContactState:
    status: str  # converged | not_converged | infeasible | time_limit
    p: np.ndarray
    v: np.ndarray  # [w; lam_eq; lam_in; tau]
    mode: Mode
    pair_states: list[str]  # per pair: open | frictionless | slipping | sticking
    sigma: np.ndarray  # per pair: the sign of a slipping pair's friction along its tangent
    iterations: int
    seconds: float
    message: str = ""
    kkt_norm: float = float("nan")
    approach_steps: int = 0
    history: list[float] = field(default_factory=list)

    @property
    def converged(self) -> bool:
        return self.status == "converged"


def start_point(problem: ContactProblem, p: np.ndarray) -> np.ndarray:
    """The undeformed state, with separating lines between every jaw piece and object."""
    x = np.zeros(problem.n_x)
    axes = np.asarray(problem.axes_guess(x, p), dtype=float).ravel()
    return np.concatenate([x, axes])


def separated(problem: ContactProblem, w: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(per pair, how deep an object penetrates its site (nondimensional, 0 if apart); w with
    every separating line at its best: the direction of least overlap, the offset midway).
    For convex pieces the least overlap over all directions is the penetration depth."""
    w = w.copy()
    h = np.asarray(problem.rows(w, p)[0], dtype=float).ravel()
    axes, pairs = np.asarray(problem.row_axes), np.asarray(problem.row_pairs)
    pushes = np.asarray(problem.row_pushes)
    depth = np.zeros(problem.n_pairs)
    for k in np.flatnonzero(axes < 0):
        depth[pairs[k]] = max(depth[pairs[k]], -h[k])
    for j in range(problem.n_axes // 2):
        site, obj = (axes == j) & pushes, (axes == j) & ~pushes
        slot = problem.n_x + 2 * j

        def overlap(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            W = np.repeat(w[:, None], len(theta), axis=1)
            W[slot] = theta
            H = np.asarray(problem.rows.map(len(theta))(W, np.repeat(p[:, None], len(theta), axis=1))[0], dtype=float)
            return -(H[site].min(axis=0) + H[obj].min(axis=0)), H

        grid = np.linspace(-np.pi, np.pi, SEPARATION_DIRECTIONS, endpoint=False)
        best = grid[int(np.argmin(overlap(grid)[0]))]
        step = 2 * np.pi / SEPARATION_DIRECTIONS
        for _ in range(30):  # narrow down around the best direction
            trial = np.array([best - step, best, best + step])
            best, step = trial[int(np.argmin(overlap(trial)[0]))], step / 2
        least, H = overlap(np.array([best]))
        w[slot] = best
        w[slot + 1] += (H[obj].min() - H[site].min()) / 2
        depth[problem.axis_pairs[j]] = max(depth[problem.axis_pairs[j]], float(least[0]))
    return np.maximum(depth, 0.0), w


def empty_mode(problem: ContactProblem) -> Mode:
    n_rows, n_objects = problem.n_rows, len(problem.structure.contacts.objects)
    return Mode(
        np.zeros(problem.n_in),
        np.zeros(problem.n_in),
        np.zeros(problem.n_axes),
        np.zeros(problem.n_axes),
        np.zeros(problem.n_pairs),
        np.zeros(n_rows),
        np.zeros((2, n_rows)),
        np.zeros((2, n_objects)),
        np.zeros(n_objects),
    )


def _solver(problem: ContactProblem, warm: bool):
    options = {**IPOPT_OPTIONS, **(WARM if warm else {})}
    return ipopt.nlp_solver("contact_warm" if warm else "contact", problem.structure, lambda: problem.nlp, options)


def _ipopt(
    problem: ContactProblem, p: np.ndarray, shift: np.ndarray, w0: np.ndarray, v_warm: np.ndarray | None, stop
) -> ipopt.IpoptResult:
    n_eq, n_in = problem.n_eq, problem.n_in
    arguments = {
        "x0": w0,
        "p": np.concatenate([p, shift]),
        "lbg": np.zeros(n_eq + n_in),
        "ubg": np.concatenate([np.zeros(n_eq), np.full(n_in, np.inf)]),
    }
    if v_warm is not None:
        parts = split(problem, v_warm)
        arguments["lam_g0"] = np.concatenate([parts.lam_eq, -parts.lam_in])
    return ipopt.solve(_solver(problem, v_warm is not None), stop=stop, **arguments)


def _from_ipopt(problem: ContactProblem, run: ipopt.IpoptResult) -> tuple[np.ndarray, np.ndarray]:
    """(v, active) of an IPOPT solution."""
    lam_eq = run.lam_g[: problem.n_eq]
    lam_in = np.maximum(-run.lam_g[problem.n_eq :], 0.0)
    h = run.g[problem.n_eq :]
    active = (lam_in > h).astype(float)  # complementarity lam h ~ 0: whichever is nearer zero says
    return np.concatenate([run.x, lam_eq, lam_in, np.zeros(problem.n_pairs)]), active


def frictionless(
    problem: ContactProblem, p: np.ndarray, previous: ContactState | None, options: ContactOptions
) -> tuple[ipopt.IpoptResult, int]:
    """IPOPT from the previous state (warm), or from the undeformed state, approaching a
    penetrating object by relaxing its rows and tightening them in steps (following the
    branch that grows from the contact-free state)."""
    stop = ipopt.deadline(options.time_limit)
    if previous is not None:
        return _ipopt(problem, p, np.zeros(problem.n_in), split(problem, previous.v).w, previous.v, stop), 0
    depth, w0 = separated(problem, start_point(problem, p), p)
    h0 = np.asarray(problem.rows(w0, p)[0], dtype=float).ravel()
    if np.all(h0 >= 0):
        return _ipopt(problem, p, np.zeros(problem.n_in), w0, None, stop), 0
    if options.penetrating_start == "refuse" and depth.max(initial=0.0) > 0:
        worst = int(np.argmax(depth))
        raise PenetratingStart(worst, float(depth[worst]))
    relaxation = np.concatenate([np.zeros(problem.n_element_in), np.maximum(-h0, 0.0) * (1 + 1e-6) + 1e-9])
    steps = int(np.clip(np.ceil(relaxation.max() / APPROACH_STEP), 2, 200))
    run, v = None, None
    for step in range(steps + 1):
        shift = relaxation * (1 - step / steps)
        run = _ipopt(problem, p, shift, w0 if run is None else run.x, v, stop)
        if not run.succeeded:
            return run, step
        v = _from_ipopt(problem, run)[0]
    return run, steps


def solve_state(
    problem: ContactProblem,
    p: np.ndarray,
    mu: np.ndarray,
    previous: ContactState | None = None,
    options: ContactOptions = ContactOptions(),
    motion: np.ndarray | None = None,
) -> ContactState:
    """The contact state at parameters p (nondimensional). `previous`: the state to start
    from, and the state friction slides from (a path's last). `motion`: instead, the rate of
    p (a single state): friction opposes the slide this motion causes at the state."""
    started = time.perf_counter()
    slides = None
    if motion is not None:
        slides = lambda v, mode, forces: _pair_slide_rates(problem, v, p, mode, forces, motion)  # noqa: E731
    elif previous is not None:
        slides = lambda v, mode, forces: _pair_slides(problem, v, p, mode, forces)  # noqa: E731
    run, approach_steps = frictionless(problem, p, previous, options)
    base = empty_mode(problem)
    if not run.succeeded:
        return _failed_state(problem, p, run, base, approach_steps, options, started)
    v, active = _from_ipopt(problem, run)
    newton_run, mode = consistent_active_set(problem, v, p, replace(base, active=active))
    iterations = run.iterations + newton_run.iterations
    sigma = np.zeros(problem.n_pairs)
    if newton_run.converged and slides is not None and np.any(mu > 0):
        if previous is not None and motion is None:
            mode = _reference(problem, mode, previous)
        newton_run, mode, sigma, rounds = _with_friction(
            problem,
            newton_run.v,
            p,
            mu,
            mode,
            slides,
            previous.sigma if previous is not None else None,
            can_stick=motion is None,
        )
        iterations += rounds
    status = "converged" if newton_run.converged else "not_converged"
    message = "" if newton_run.converged else "the contact's KKT system did not converge (Newton, active set)"
    states = _pair_states(problem, newton_run.v, mode, mu, sigma)
    return ContactState(
        status,
        p,
        newton_run.v,
        mode,
        states,
        sigma,
        iterations,
        time.perf_counter() - started,
        message,
        newton_run.norm,
        approach_steps,
        newton_run.history,
    )


def _failed_state(problem, p, run, base, approach_steps, options, started) -> ContactState:
    """The state IPOPT stopped at without a solution, every pair open, and why it stopped."""
    states = ["open"] * problem.n_pairs
    v = np.concatenate([run.x, np.zeros(problem.n_eq + problem.n_in + problem.n_pairs)])
    message = f"IPOPT: {run.return_status}"
    if run.status == "time_limit":
        message = f"stopped by the time limit of {options.time_limit:g} s (IPOPT: {run.return_status})"
    elif run.status == "infeasible":
        message = (
            "no state keeps every site out of every object (IPOPT: Infeasible_Problem_Detected): "
            "the objects leave the sites no room"
        )
    return ContactState(
        run.status if run.status != "optimal" else "not_converged",
        p,
        v,
        base,
        states,
        np.zeros(problem.n_pairs),
        run.iterations,
        time.perf_counter() - started,
        message,
        approach_steps=approach_steps,
    )


def _row_forces(problem: ContactProblem, v: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Per contact row, the size of its normal force on the site (0 for object rows)."""
    parts = split(problem, v)
    normals = np.asarray(problem.rows(parts.w, p)[1], dtype=float)
    lam = parts.lam_in[problem.n_element_in :]
    return np.maximum(lam, 0.0) * np.linalg.norm(normals, axis=0) * np.asarray(problem.row_pushes, dtype=float)


def _pair_sums(problem: ContactProblem, per_row: np.ndarray) -> np.ndarray:
    sums = np.zeros(problem.n_pairs)
    np.add.at(sums, np.asarray(problem.row_pairs, dtype=int), per_row)
    return sums


def _reference(problem: ContactProblem, mode: Mode, reference: ContactState) -> Mode:
    """The mode's reference state: where the sites' points and the objects were."""
    w = split(problem, reference.v).w
    points_old = np.asarray(problem.rows(w, reference.p)[2], dtype=float)
    origins_old, angles_old = (np.asarray(a, dtype=float) for a in problem.frames(w, reference.p))
    return replace(mode, points_old=points_old, origins_old=origins_old, angles_old=angles_old.ravel())


def _with_friction(problem, v, p, mu, mode, slides, previous_sigma, can_stick: bool):
    """Friction on every touching pair with mu > 0: slipping against its slide, or sticking
    where slipping would contradict itself (on a path; a single state without history
    reports such a pair as sticking with no friction force)."""
    row_pairs = np.asarray(problem.row_pairs, dtype=int)
    sigma, sticking = np.zeros(problem.n_pairs), np.zeros(problem.n_pairs)
    forces = _row_forces(problem, v, p)
    slide = slides(v, mode, forces)
    for j in np.flatnonzero((_pair_sums(problem, forces) > 0) & (mu > 0)):
        before = previous_sigma[j] if previous_sigma is not None else 0.0
        if abs(slide[j]) > 1e-13:
            sigma[j] = -np.sign(slide[j])
        elif before:
            sigma[j] = before
        elif can_stick:
            sticking[j] = 1.0
    run, rounds = None, 0
    for _ in range(FRICTION_ROUNDS):
        forces = _row_forces(problem, v, p)
        totals = _pair_sums(problem, forces)
        weights = np.where(totals[row_pairs] > 0, forces / np.maximum(totals[row_pairs], 1e-300), 0.0)
        phi_rows = np.where(sticking[row_pairs] > 0, 0.0, mu[row_pairs] * sigma[row_pairs])
        phi = np.concatenate([np.zeros(problem.n_element_in), phi_rows])
        mode = replace(mode, phi=phi, stick=sticking.copy(), weights=weights)
        run, mode = consistent_active_set(problem, v, p, mode)
        rounds += run.iterations
        if not run.converged:
            break
        v = run.v
        changed = False
        forces = _row_forces(problem, v, p)
        totals = _pair_sums(problem, forces)
        slide = slides(v, mode, forces)
        tau = split(problem, v).tau
        for j in range(problem.n_pairs):
            if mu[j] <= 0 or totals[j] <= 0:
                continue
            if sticking[j] and abs(tau[j]) > mu[j] * totals[j] * (1 + 1e-9):
                sticking[j], sigma[j], changed = 0.0, np.sign(tau[j]), True
            elif not sticking[j] and sigma[j] * slide[j] > CONSISTENCY:
                if can_stick:
                    sticking[j], changed = 1.0, True
                else:  # neither direction holds at a single state: it sticks, by an unknown force
                    sigma[j], changed = 0.0, True
            elif not sticking[j] and not sigma[j] and abs(slide[j]) > 1e-13 and can_stick:
                sigma[j], changed = -np.sign(slide[j]), True
        if not changed:
            break
    return run, mode, np.where(sticking > 0, 0.0, sigma), rounds


def _pair_slide_rates(problem, v, p, mode, forces, motion) -> np.ndarray:
    """Per pair, the normal-force weighted rate of slide at the state as p moves at `motion`
    (the KKT system's sensitivity, the reference frozen at the state itself)."""
    arguments = mode.arguments(v, p)
    F_v = np.asarray(problem.kkt(**arguments)["J"], dtype=float)
    F_p = np.asarray(problem.kkt_parameters(**arguments)["Fp"], dtype=float)
    v_rate = -np.linalg.solve(F_v, F_p @ motion)
    w = split(problem, v).w
    here = _reference(problem, mode, ContactState("converged", p, v, mode, [], np.zeros(0), 0, 0.0))
    out = problem.slides(w, p, here.points_old, here.origins_old, here.angles_old)
    rates = np.asarray(out[1], dtype=float) @ v_rate[: problem.n_w] + np.asarray(out[2], dtype=float) @ motion
    totals = _pair_sums(problem, forces)
    return np.where(totals > 0, _pair_sums(problem, forces * rates) / np.maximum(totals, 1e-300), 0.0)


def _pair_slides(problem, v, p, mode, forces) -> np.ndarray:
    """Per pair, the normal-force weighted slide of its rows from the reference state."""
    w = split(problem, v).w
    slides = np.asarray(
        problem.slides(w, p, mode.points_old, mode.origins_old, mode.angles_old)[0], dtype=float
    ).ravel()
    totals = _pair_sums(problem, forces)
    weighted = _pair_sums(problem, forces * slides)
    return np.where(totals > 0, weighted / np.maximum(totals, 1e-300), 0.0)


def _pair_states(problem, v, mode, mu, sigma) -> list[str]:
    active = mode.active[problem.n_element_in :] > 0.5
    touching = np.zeros(problem.n_pairs, dtype=bool)
    for k, pair in enumerate(problem.row_pairs):
        touching[pair] |= bool(active[k])
    out = []
    for j in range(problem.n_pairs):
        if not touching[j]:
            out.append("open")
        elif mode.stick[j] > 0.5:
            out.append("sticking")
        elif sigma[j] != 0 and mu[j] > 0:
            out.append("slipping")
        else:
            out.append("frictionless")
    return out
