"""The one way flexmech runs IPOPT: allowlisted options, solvers built once per structure and
setting, CasADi's success flag checked, and one mapping of IPOPT's return status.

Every NLP (bounded equilibrium, design optimization, minimum energy, and contact next) builds
its solver through nlp_solver() and runs it through solve(). The pip wheel's IPOPT has MUMPS
and SPRAL; asking for an HSL solver (ma27, ma57, ...) fails and can crash the process later,
so only those two are accepted.
"""

from __future__ import annotations

import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from flexmech.service.deadline import ends_after, passed

LINEAR_SOLVERS = ("mumps", "spral")

# The IPOPT options a caller may set, with a check of the value.
_POSITIVE = (float, lambda v: v > 0)
ALLOWED_OPTIONS: dict[str, tuple[type, Callable[[Any], bool]]] = {
    "tol": _POSITIVE,
    "constr_viol_tol": _POSITIVE,
    "acceptable_tol": _POSITIVE,
    "dual_inf_tol": _POSITIVE,
    "max_iter": (int, lambda v: v >= 0),
    "max_wall_time": _POSITIVE,
    "max_cpu_time": _POSITIVE,
    "mu_strategy": (str, lambda v: v in ("monotone", "adaptive")),
    "linear_solver": (str, lambda v: v in LINEAR_SOLVERS),
    "hessian_approximation": (str, lambda v: v in ("exact", "limited-memory")),
    "bound_relax_factor": (float, lambda v: v >= 0),
    "print_level": (int, lambda v: 0 <= v <= 12),
    "mu_init": _POSITIVE,
    "warm_start_init_point": (str, lambda v: v in ("yes", "no")),
    "warm_start_bound_push": _POSITIVE,
    "warm_start_mult_bound_push": _POSITIVE,
    "warm_start_slack_bound_push": _POSITIVE,
}

# IPOPT's return status -> ours (optimal | acceptable | infeasible | not_converged | time_limit).
STATUS = {
    "Solve_Succeeded": "optimal",
    "Solved_To_Acceptable_Level": "acceptable",
    "Infeasible_Problem_Detected": "infeasible",
    "Maximum_Iterations_Exceeded": "not_converged",
    "Maximum_CpuTime_Exceeded": "time_limit",
    "Maximum_WallTime_Exceeded": "time_limit",
}


class IpoptOptionError(ValueError):
    """An IPOPT option that is not allowed or has a bad value; `option` names it."""

    def __init__(self, option: str, problem: str):
        self.option = option
        super().__init__(f"{option}: {problem}")
        self.problem = problem

    def __reduce__(self):  # pickled with its fields, so it crosses from a worker process whole
        return (IpoptOptionError, (self.option, self.problem))


def checked_options(options: dict[str, Any]) -> tuple[tuple[str, Any], ...]:
    """The options, validated against the allowlist, as a hashable (sorted) tuple; the linear
    solver defaults to MUMPS."""
    out = {"linear_solver": "mumps"}
    for name, value in options.items():
        if name not in ALLOWED_OPTIONS:
            raise IpoptOptionError(
                name, f"not an IPOPT option flexmech sets (options: {', '.join(sorted(ALLOWED_OPTIONS))})"
            )
        kind, check = ALLOWED_OPTIONS[name]
        if isinstance(value, bool) or not isinstance(value, (kind, int) if kind is float else kind):
            raise IpoptOptionError(name, f"expected a {kind.__name__}, got {value!r}")
        if not check(value):
            hint = f" (the wheel's IPOPT has {' and '.join(LINEAR_SOLVERS)})" if name == "linear_solver" else ""
            raise IpoptOptionError(name, f"value {value!r} is not allowed{hint}")
        out[name] = value
    return tuple(sorted(out.items()))


_SOLVERS: OrderedDict[tuple, ca.Function] = OrderedDict()
_WATCHES: dict[int, _Watch] = {}  # id(solver) -> its iteration hook
MAX_SOLVERS = 64  # the least recently used go first


class _Watch(ca.Callback):
    """IPOPT's iteration hook: asks `stop` (set for the duration of a solve) whether to end
    the run now (a cancelled job, a deadline): IPOPT then returns User_Requested_Stop."""

    def __init__(self, name: str, n_x: int, n_g: int, n_p: int):
        ca.Callback.__init__(self)
        self.sizes = {"x": n_x, "lam_x": n_x, "g": n_g, "lam_g": n_g, "f": 1, "lam_p": n_p}
        self.stop: Callable[[], bool] | None = None
        self.stopped = False
        self.construct(name, {})

    def get_n_in(self) -> int:
        return ca.nlpsol_n_out()

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return ca.nlpsol_out(i)

    def get_name_out(self, i: int) -> str:
        return "ret"

    def get_sparsity_in(self, i: int) -> ca.Sparsity:
        n = self.sizes.get(ca.nlpsol_out(i), 0)
        return ca.Sparsity.scalar() if ca.nlpsol_out(i) == "f" else ca.Sparsity.dense(n, 1)

    def eval(self, arg):
        if self.stop is not None and self.stop():
            self.stopped = True
            return [1]
        return [0]


def nlp_solver(name: str, key: Any, problem: Callable[[], dict], options: dict[str, Any]) -> ca.Function:
    """IPOPT on the NLP that problem() states ({x, p, f, g} of SX), built once per (name, key,
    options): key identifies the structure (e.g. a Structure, or a design problem's key)."""
    settings = checked_options(options)
    cache_key = (name, key, settings)
    if cache_key in _SOLVERS:
        _SOLVERS.move_to_end(cache_key)
        return _SOLVERS[cache_key]
    ipopt = {f"ipopt.{k}": v for k, v in settings}
    nlp = problem()
    p = nlp.get("p")
    watch = _Watch(
        f"{name}_watch", nlp["x"].numel(), nlp["g"].numel() if "g" in nlp else 0, 0 if p is None else p.numel()
    )
    solver = ca.nlpsol(
        name,
        "ipopt",
        nlp,
        {"print_time": False, "ipopt.sb": "yes", "ipopt.print_level": 0, "iteration_callback": watch, **ipopt},
    )
    _SOLVERS[cache_key] = solver
    _WATCHES[id(solver)] = watch
    if len(_SOLVERS) > MAX_SOLVERS:
        _WATCHES.pop(id(_SOLVERS.popitem(last=False)[1]), None)
    return solver


def cached_solvers() -> int:
    """How many solvers are built and kept (for tests and diagnostics)."""
    return len(_SOLVERS)


def deadline(seconds: float | None) -> Callable[[], bool] | None:
    """A stop() for solve(): True once `seconds` have passed, or the call's deadline
    (service.deadline; None: never)."""
    if seconds is None:
        return None
    end = ends_after(seconds)
    return lambda: passed(end)


@dataclass
class IpoptResult:
    status: str  # optimal | acceptable | infeasible | not_converged | time_limit
    return_status: str  # IPOPT's own words
    x: np.ndarray
    f: float
    g: np.ndarray
    lam_g: np.ndarray
    lam_x: np.ndarray
    iterations: int
    seconds: float
    history: dict = field(repr=False, default_factory=dict)  # IPOPT's per-iteration record (obj, inf_pr, inf_du)

    @property
    def succeeded(self) -> bool:
        return self.status in ("optimal", "acceptable")


def solve(
    solver: ca.Function, stop: Callable[[], bool] | None = None, stop_status: str = "time_limit", **arguments
) -> IpoptResult:
    """Run a solver (x0, p, lbx, ubx, lbg, ubg); the status is 'optimal' or 'acceptable' only
    when CasADi reports success. stop() is asked at every iteration: True ends the run with
    `stop_status`."""
    started = time.perf_counter()
    watch = _WATCHES.get(id(solver))
    if watch is not None:
        watch.stop, watch.stopped = stop, False
    try:
        solution = solver(**arguments)
    finally:
        if watch is not None:
            watch.stop = None
    stats = solver.stats()
    return_status = str(stats.get("return_status", "unknown"))
    status = STATUS.get(return_status, "not_converged")
    if status in ("optimal", "acceptable") and not stats.get("success", False):
        status = "not_converged"
    if watch is not None and watch.stopped:
        status = stop_status

    def array(name: str) -> np.ndarray:
        return np.asarray(solution[name], dtype=float).ravel()

    return IpoptResult(
        status,
        return_status,
        array("x"),
        float(solution["f"]),
        array("g"),
        array("lam_g"),
        array("lam_x"),
        int(stats.get("iter_count", 0)),
        time.perf_counter() - started,
        stats.get("iterations") or {},
    )
