"""Analyses on compiled mechanisms: equilibrium, inverse, sweeps, the compiled fast path, CLI."""

from service.equilibrium import EquilibriumResult, NewtonOptions, solve_equilibrium
from service.inverse import inverse_wrenches
from service.sweep import SweepResult, solve_for_target, sweep
from service.stiffness import tangent_stiffness

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
