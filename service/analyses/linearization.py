"""The linearization analysis: the tangent stiffness K_T (and the seed-000 terms I-III where
they apply) at the equilibrium under the document's loads, or undeformed."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

from models import Mechanism, MechanismError
from service.analyses.base import Analysis, AnalysisOptions, AnalysisResult
from service.requests import under
from service.solvers.equilibrium import solve_equilibrium
from service.solvers.newton import NewtonOptions
from service.solvers.reports import coordinate_units, output_units, plain, stiffness_dict


def linearization_report(mech: Mechanism, options: NewtonOptions, at: str = "equilibrium") -> dict:
    """K_T and its terms at the equilibrium under the document's loads (or undeformed)."""
    if at not in ("equilibrium", "undeformed"):
        raise MechanismError("/at", f"unknown state '{at}' (equilibrium, undeformed)")
    report: dict[str, Any] = {"analysis": "linearization", "name": mech.document.name, "at": at}
    z = None
    if at == "equilibrium":
        try:
            result = solve_equilibrium(mech, options)
        except MechanismError as exc:
            raise under("/document", exc) from None
        report.update(result.summary(), output_units=output_units(mech), displacement_units=coordinate_units(mech))
        if not result.converged:
            return plain(report)
        z = result.z
    else:
        report.update(status="converged", message="", iterations=0)
    report["stiffness"] = stiffness_dict(mech, z)
    return plain(report)


class LinearizationOptions(AnalysisOptions):
    at: Literal["equilibrium", "undeformed"] = Field(
        "equilibrium", description="the state: the equilibrium under the document's loads, or undeformed"
    )


class LinearizationReport(AnalysisResult):
    at: str
    stiffness: dict | None = Field(None, description="K_T, its terms, the units of its rows and columns")


class LinearizationAnalysis(Analysis):
    name = "linearization"
    summary = "The tangent stiffness K_T at the equilibrium (or undeformed: at=undeformed), in document units"
    Options = LinearizationOptions
    Result = LinearizationReport

    def report(self, mech: Mechanism, newton: NewtonOptions, options: LinearizationOptions) -> dict:
        return linearization_report(mech, newton, options.at)


LINEARIZATION = LinearizationAnalysis()
