"""Analyses on compiled mechanisms: equilibrium, inverse, sweeps, the compiled fast path, CLI.

The names below are imported when first asked for (PEP 562), so that a subpackage that needs
none of them (the command line answering --help) does not pay for NumPy and CasADi."""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from flexmech.service.solvers.equilibrium import EquilibriumResult, solve_equilibrium
    from flexmech.service.solvers.inverse import inverse_wrenches
    from flexmech.service.solvers.newton import NewtonOptions
    from flexmech.service.solvers.stiffness import tangent_stiffness
    from flexmech.service.solvers.sweep import SweepResult, solve_for_target, sweep

# name -> the module that defines it
_PUBLIC = {
    "EquilibriumResult": "flexmech.service.solvers.equilibrium",
    "NewtonOptions": "flexmech.service.solvers.newton",
    "solve_equilibrium": "flexmech.service.solvers.equilibrium",
    "inverse_wrenches": "flexmech.service.solvers.inverse",
    "SweepResult": "flexmech.service.solvers.sweep",
    "solve_for_target": "flexmech.service.solvers.sweep",
    "sweep": "flexmech.service.solvers.sweep",
    "tangent_stiffness": "flexmech.service.solvers.stiffness",
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
