"""The state a vibration analysis linearizes about: the equilibrium under the document's loads,
or the undeformed state. Its report is the equilibrium's status, residual and warnings (its
displacements and outputs are the equilibrium analysis')."""

from __future__ import annotations

from typing import Any

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.service.requests import under
from flexmech.service.solvers.equilibrium import solve_equilibrium
from flexmech.service.solvers.newton import NewtonOptions

SHOWN = (
    "status",
    "message",
    "iterations",
    "residual_norm",
    "residual_unit",
    "residual_moment",
    "residual_moment_unit",
    "solver_residual",
    "solver_residual_unit",
)


MAX_OWN_UNKNOWNS = 96  # the elements' own unknowns a modal graph takes: 72 build in 2.6 s, 144 in 14 s


def check_modal_cost(mech: Mechanism) -> None:
    """Refused before any modal graph is built: its Hessians grow faster than the square of the
    elements' own unknowns (rotations, and strains with shear or axial strain)."""
    own = 0
    for name, element in mech.document.elements.items():
        intervals, degree = getattr(element, "intervals", 0), getattr(element, "degree", 0)
        if getattr(element, "discretization", None) == "elements":
            own += (
                intervals
                * degree
                * (1 + int(bool(getattr(element, "shear", False))) + int(bool(getattr(element, "axial", False))))
            )
            if own > MAX_OWN_UNKNOWNS:
                raise MechanismError(
                    f"/document/elements/{name}/intervals",
                    f"the vibration analyses take at most {MAX_OWN_UNKNOWNS} unknowns of the elements' own "
                    "(intervals x degree, times 3 with shear and axial strain): use fewer elements or a lower degree",
                )


def vibration_state(mech: Mechanism, newton: NewtonOptions, at: str, report: dict[str, Any]) -> np.ndarray | None:
    """z about which to linearize, its status written into `report`; None if the equilibrium
    was not found (the report says why). Its modal cost is checked first."""
    check_modal_cost(mech)
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
