"""Analyses on compiled mechanisms: equilibrium, inverse, sweeps, the compiled fast path, CLI.

The names below are imported when first asked for (PEP 562), so that a subpackage that needs
none of them (the command line answering --help) does not pay for NumPy and CasADi."""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from service.solvers.equilibrium import EquilibriumResult, solve_equilibrium
    from service.solvers.inverse import inverse_wrenches
    from service.solvers.newton import NewtonOptions
    from service.solvers.stiffness import tangent_stiffness
    from service.solvers.sweep import SweepResult, solve_for_target, sweep

# name -> the module that defines it
_PUBLIC = {
    "EquilibriumResult": "service.solvers.equilibrium",
    "NewtonOptions": "service.solvers.newton",
    "solve_equilibrium": "service.solvers.equilibrium",
    "inverse_wrenches": "service.solvers.inverse",
    "SweepResult": "service.solvers.sweep",
    "solve_for_target": "service.solvers.sweep",
    "sweep": "service.solvers.sweep",
    "tangent_stiffness": "service.solvers.stiffness",
}

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


def __getattr__(name: str) -> Any:
    if name not in _PUBLIC:
        raise AttributeError(f"module 'service' has no attribute '{name}'")
    return getattr(importlib.import_module(_PUBLIC[name]), name)
