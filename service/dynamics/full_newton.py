"""Full Newton on a structure's step system (service.dynamics.kernel_system): for a step that
modified Newton on a window's older factors does not settle (service.dynamics.engine's rescue,
sdirk4's stage rescue in service.dynamics.stage_window)."""

from __future__ import annotations

import casadi as ca

from flexmech.service.dynamics.kernel_records import Evaluation, Factors, StepInputs
from flexmech.service.dynamics.kernel_system import NEWTON_TOLERANCE, StepSystem


def newton(system: StepSystem, Z, si: StepInputs, iterations: int) -> tuple[ca.MX, Factors, Evaluation]:
    """(Z, its factors, its evaluation) after up to `iterations` iterations of full Newton from Z,
    the factors made again at every one. An iteration after the residual is below the tolerance
    is skipped as a whole (a branch: a rescue that settles in three iterations costs four, not
    all sixteen; the values are those of running them all)."""
    carry, parts = [Z, ca.MX(ca.inf)], si.parts()
    for _ in range(iterations):
        carry = gated_iteration(system, si)(*carry, *parts)
    Z, one = carry[0], ca.MX(1)
    factors = system.factorize(Z, si)
    return Z, factors, system.evaluate(Z, one, si, factors.kept_reverse)


def gated_iteration(system: StepSystem, si: StepInputs) -> ca.Function:
    """(Z, the residual's norm before Z, the step's inputs...) -> (Z after one full Newton
    iteration, the norm at Z): the iteration where that norm was above the tolerance, else Z as
    it is. Made once per system and shape of the step's inputs."""
    key = tuple(part.sparsity().shape for part in si.parts())
    if key not in system.newton_iterations:
        made = si.symbols()
        Z, one, before = ca.MX.sym("Z", system.n_z), ca.MX(1), ca.MX.sym("before")
        factors = system.factorize(Z, made)
        ev = system.evaluate(Z, one, made, factors.kept_reverse)
        Z_next = ca.if_else(ev.norm > NEWTON_TOLERANCE, Z - system.solve(ev, one, factors), Z)
        inputs = [Z, before, *made.parts()]
        step = ca.Function("newton_iteration", inputs, [Z_next, ev.norm])
        idle = ca.Function("newton_idle", inputs, [Z, before])
        switch = ca.Function.if_else("newton_switch", step, idle)
        system.newton_iterations[key] = ca.Function("newton_gated", inputs, switch(before > NEWTON_TOLERANCE, *inputs))
    return system.newton_iterations[key]
