"""The state a vibration analysis linearizes about: the equilibrium under the document's loads,
or the undeformed state. Its report is the equilibrium's status, residual and warnings (its
displacements and outputs are the equilibrium analysis')."""

from __future__ import annotations

from typing import Any

import numpy as np

from models import Mechanism, MechanismError
from service.requests import under
from service.solvers.equilibrium import solve_equilibrium
from service.solvers.newton import NewtonOptions

SHOWN = ("status", "message", "iterations", "residual_norm", "residual_moment", "residual_unit", "solver_residual")


def vibration_state(mech: Mechanism, newton: NewtonOptions, at: str, report: dict[str, Any]) -> np.ndarray | None:
    """z about which to linearize, its status written into `report`; None if the equilibrium
    was not found (the report says why)."""
    if at != "equilibrium":
        report.update(status="converged", message="", iterations=0)
        return np.zeros(mech.n_free)
    try:
        result = solve_equilibrium(mech, newton)
    except MechanismError as exc:
        raise under("/document", exc) from None
    summary = result.summary_of_state()
    report.update({key: summary[key] for key in SHOWN if key in summary})
    report["seconds"] = result.seconds
    report["warnings"] = summary["warnings"]
    return result.z if result.converged else None
