"""Analyses on compiled mechanisms: equilibrium, inverse, sweeps, the compiled fast path, CLI."""

from service.solvers.equilibrium import EquilibriumResult, NewtonOptions, solve_equilibrium
from service.solvers.inverse import inverse_wrenches
from service.solvers.stiffness import tangent_stiffness
from service.solvers.sweep import SweepResult, solve_for_target, sweep

__all__ = [
    "EquilibriumResult",
    "NewtonOptions",
    "solve_equilibrium",
    "inverse_wrenches",
    "SweepResult",
    "solve_for_target",
    "sweep",
    "tangent_stiffness",
]
