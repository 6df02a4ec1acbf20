"""A window of steps in one call: each step's Newton solve inside CasADi (small systems: the
chord method on a symbolic inverse; larger ones: Newton twice, then the chord method with
numeric QR solves; both can be code-generated), the steps chained by mapaccum, the whole window
compiled with the system compiler and cached on disk like the equilibrium fast path. Python
is called once per window, not once per Newton iteration.

The state carried from step to step is s = [x; v; a; qdd; lam]. Per step the window also
returns the monitor (T, V_held, input power, damping power, motion forces) and the step's
residual (inf-norm, with the constraint rows scaled so that one tolerance serves both), by
which the caller finds a step that did not converge.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path

import casadi as ca

from models.graph_cache import code_version
from models.structure import Structure
from service.dynamics.functions import form_of, monitor_function
from service.dynamics.schemes import Scheme
from service.fastpath import compile_function

NEWTON_TOLERANCE = 1e-10  # nondimensional residual of a step's equations (forces)
CONSTRAINT_TOLERANCE = 1e-13  # and of its constraints (lengths, angles)
MAX_NEWTON = 25
CHORD_ITERATIONS = 4  # residual-only iterations after the first Newton step of a window step
CHORD_SIZE = 20  # unknowns up to which the chord method on a symbolic inverse beats Newton (measured)

WINDOW = 50  # steps per call


@lru_cache(maxsize=16)
def window_function(structure: Structure, scheme: Scheme, moving: tuple[int, ...], steps: int = WINDOW,
                    compiled: bool = True) -> ca.Function:
    """(s0, h, P, PDOT, PDDOT, damping, mask) -> (S, MONITOR, RESIDUAL), a column per step."""
    form = form_of(structure, moving)
    n, m, n_p, k = len(form.unknowns), form.n_equalities, form.constraints.size1_in(1), len(moving)
    u = ca.SX.sym("u", n + m)
    state = ca.SX.sym("s", 4 * n + m)
    x, v, a, qdd = (state[i * n:(i + 1) * n] for i in range(4))
    h, damping = ca.SX.sym("h"), ca.SX.sym("damping")
    p, mask = ca.SX.sym("p", n_p), ca.SX.sym("mask", n_p)
    pdot, pddot = ca.SX.sym("pdot", k), ca.SX.sym("pddot", k)
    s = scheme

    def advance(unknowns):
        a1 = ((1 - s.alpha_f) * unknowns[:n] + s.alpha_f * qdd - s.alpha_m * a) / (1 - s.alpha_m)
        x1 = x + h * v + h**2 * ((0.5 - s.beta) * a + s.beta * a1)
        v1 = v + h * ((1 - s.gamma) * a + s.gamma * a1)
        return x1, v1, a1

    x1, v1, _ = advance(u)
    # the constraint rows scaled so that NEWTON_TOLERANCE on them is CONSTRAINT_TOLERANCE on g
    F = ca.vertcat(form.equations(x1, v1, u[:n], u[n:], p, pdot, pddot, damping),
                   form.constraints(x1, p) * (NEWTON_TOLERANCE / CONSTRAINT_TOLERANCE))
    parameters = ca.vertcat(state, h, p, pdot, pddot, damping)
    residual = ca.Function("step_residual", [u, parameters], [F])
    guess = ca.vertcat(qdd, state[4 * n:])
    jacobian = ca.Function("step_jacobian", [u, parameters], [F, ca.jacobian(F, u)])
    solution = ca.SX.sym("solution", n + m)
    x1, v1, a1 = advance(solution)
    left = ca.norm_inf(residual(solution, parameters))
    qdd1, lam1 = solution[:n], solution[n:]
    T, V, power, dissipation, Q = monitor_function(structure, moving)(x1, v1, qdd1, lam1, p, pdot, pddot, mask, damping)
    inputs = [state, h, p, pdot, pddot, damping, mask]
    finish = ca.Function("step_finish", [solution, *inputs],
                         [ca.vertcat(x1, v1, a1, qdd1, lam1), ca.vertcat(T, V, power, dissipation, Q), left])
    if n + m <= CHORD_SIZE:  # all in SX: the symbolic inverse is small
        one = ca.Function("one_step", inputs, finish(_chord_newton(residual, jacobian, guess, parameters), *inputs))
    else:  # the chord method with a numeric factorization per iteration (MX)
        start = ca.Function("step_start", inputs, [guess, parameters])
        symbols = [ca.MX.sym(name, q.shape) for name, q in zip(("s", "h", "p", "pdot", "pddot", "damping", "mask"),
                                                              inputs)]
        first, known = start(*symbols)
        one = ca.Function("one_step", symbols, finish(_chord_newton_numeric(residual, jacobian, first, known), *symbols))
    window = one.mapaccum("dynamics_window", steps, [0], [0])
    if not compiled:
        return window
    method = "chord" if n + m <= CHORD_SIZE else "chord_qr"
    key = f"{structure.key}|{code_version()}|{_own_version()}|{scheme}|{moving}|{steps}|{method}"
    return compile_function(window, key)[0]


def _chord_newton(residual: ca.Function, jacobian: ca.Function, u0, parameters) -> ca.SX:
    """Newton with the Jacobian of the first iterate kept (the chord method): one Jacobian and
    CHORD_ITERATIONS + 1 residuals per step instead of a Jacobian per iteration. The step's
    first guess, the last accelerations, is close: the iteration contracts by orders of
    magnitude each time. A step it does not settle is cut from the window and solved by full
    Newton (service.dynamics.stepping)."""
    F0, J0 = jacobian(u0, parameters)
    inverse = ca.solve(J0, ca.SX.eye(J0.shape[0]))
    u = u0 - ca.mtimes(inverse, F0)
    for _ in range(CHORD_ITERATIONS):
        u = u - ca.mtimes(inverse, residual(u, parameters))
    return u


def _chord_newton_numeric(residual: ca.Function, jacobian: ca.Function, u0: ca.MX, parameters: ca.MX) -> ca.MX:
    """Newton twice, then the chord method on the second Jacobian, for larger systems: each
    solve factors numerically (QR), a few thousand flops against a Jacobian's million."""
    F0, J0 = jacobian(u0, parameters)
    u = u0 - ca.solve(J0, F0, "qr")
    F1, J1 = jacobian(u, parameters)  # a second Newton step: stiff links move the Jacobian in one step
    u = u - ca.solve(J1, F1, "qr")
    for _ in range(CHORD_ITERATIONS - 1):
        u = u - ca.solve(J1, residual(u, parameters), "qr")
    return u


@lru_cache(maxsize=1)
def _own_version() -> str:
    """A hash of the sources the window's graph comes from: a change there builds new libraries."""
    digest = hashlib.sha256()
    here = Path(__file__).resolve().parent
    for name in ("window.py", "functions.py", "schemes.py"):
        digest.update((here / name).read_bytes())
    return digest.hexdigest()[:12]
