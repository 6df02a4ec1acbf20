"""flexmech: how planar compliant mechanisms deform, move and touch, exactly.

    >>> import flexmech
    >>> gripper = flexmech.load("gripper", model="partial_nonlinear")
    >>> closing = flexmech.solve_for_target(gripper, "/loads/actuation/force/1", "end_effector.x", 0.0)
    >>> print(f"{closing.value:.4f} {closing.unit}")
    77.0346 uN

The public surface is what this module lists (load, solve, solve_for_target, sweep, modes,
simulate, Client, MechanismError, __version__); the subpackages flexmech.models,
flexmech.service and flexmech.api are private and may move. Names are imported when first asked
for, so `import flexmech` (and the light HTTP client) stays quick.
"""

from __future__ import annotations

import importlib
from importlib.metadata import PackageNotFoundError, version
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from flexmech.api.client import AsyncClient, Client  # noqa: F401 (the lazy names, for type checkers)
    from flexmech.calls import load, modes, simulate, solve, solve_for_target, sweep  # noqa: F401
    from flexmech.models import Mechanism, MechanismError  # noqa: F401

try:
    __version__ = version("flexmech")
except PackageNotFoundError:  # the sources without an install
    __version__ = "unknown"

_PUBLIC = {
    "load": "flexmech.calls",
    "solve": "flexmech.calls",
    "solve_for_target": "flexmech.calls",
    "sweep": "flexmech.calls",
    "modes": "flexmech.calls",
    "simulate": "flexmech.calls",
    "Client": "flexmech.api.client",
    "AsyncClient": "flexmech.api.client",
    "Mechanism": "flexmech.models",
    "MechanismError": "flexmech.models",
}

__all__ = [*_PUBLIC, "__version__"]


def __getattr__(name: str) -> Any:
    if name not in _PUBLIC:
        raise AttributeError(f"module 'flexmech' has no attribute '{name}'")
    return getattr(importlib.import_module(_PUBLIC[name]), name)


def __dir__() -> list[str]:
    return sorted(__all__)
