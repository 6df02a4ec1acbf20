"""Analyses on compiled mechanisms: equilibrium, inverse, sweeps, the compiled fast path, CLI."""

from service.equilibrium import EquilibriumResult, NewtonOptions, solve_equilibrium
from service.inverse import inverse_wrenches
from service.stiffness import tangent_stiffness
from service.sweep import SweepResult, solve_for_target, sweep

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
