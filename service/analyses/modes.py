"""The modes analysis: the lowest natural frequencies and mass-normalized mode shapes of a
mechanism about its equilibrium under the document's loads (prestress and load stiffness
included), or about the undeformed state (service.vibration)."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, Field

from models import Mechanism, MechanismError
from service.analyses.base import Analysis, AnalysisOptions, AnalysisResult
from service.requests import under
from service.solvers.equilibrium import solve_equilibrium
from service.solvers.newton import NewtonOptions
from service.solvers.reports import plain
from service.vibration.modes import mechanism_modes
from service.vibration.report import modes_report


class ModesOptions(AnalysisOptions):
    count: int = Field(6, ge=1, le=500, description="how many of the lowest modes")
    at: Literal["equilibrium", "undeformed"] = Field(
        "equilibrium", description="the state: the equilibrium under the document's loads, or undeformed"
    )
    shapes: bool = Field(True, description="report each mode's shape (bodies and the elements' mass points)")


class Mode(BaseModel):
    mode: int
    kind: Literal["elastic", "rigid", "unstable"] = Field(
        description="rigid: zero frequency (a motion nothing resists); unstable: omega^2 < 0 (a buckled state)"
    )
    omega: float = Field(description="rad/s (for an unstable mode, the rate its motion grows at)")
    frequency: float | None = Field(description="Hz (elastic modes)")
    period: float | None = Field(description="s (elastic modes)")
    omega_squared: float
    effective_mass: dict[str, float] = Field(description="along x and y, in the document's mass unit")
    effective_mass_fraction: dict[str, float | None] = Field(description="of the mechanism's mass, along x and y")
    energy_shares: dict[str, float] = Field(
        description="the share of the mode's kinetic energy in each body and element ('bodies/<name>', 'elements/<name>')"
    )
    shape: dict[str, Any] | None = None


class ModesReport(AnalysisResult):
    at: str
    coordinates: str | None = Field(
        None,
        description="elements: the energy form's unknowns (elements with their own mass); "
        "bodies: the bodies' coordinates, the elements massless and condensed",
    )
    available: int | None = Field(None, description="how many modes the mechanism has")
    total_mass: float | None = None
    modes: list[Mode] = Field(default_factory=list)
    points: dict[str, list[list[float]]] = Field(
        default_factory=dict, description="where each element's mass points stand (the shapes' points)"
    )


def modes_analysis_report(mech: Mechanism, newton: NewtonOptions, options: ModesOptions) -> dict[str, Any]:
    report: dict[str, Any] = {"analysis": "modes", "name": mech.document.name, "at": options.at}
    z = None
    if options.at == "equilibrium":
        try:
            result = solve_equilibrium(mech, newton)
        except MechanismError as exc:
            raise under("/document", exc) from None
        report.update(result.summary())
        if not result.converged:
            return plain(report)
        z = result.z
    else:
        report.update(status="converged", message="", iterations=0)
    report.update(modes_report(mech, mechanism_modes(mech, z, options.count), options.shapes))
    unstable = [m["mode"] for m in report["modes"] if m["kind"] == "unstable"]
    if unstable:
        report.setdefault("warnings", []).append(
            f"the state is unstable: mode(s) {', '.join(map(str, unstable))} have omega^2 < 0"
        )
    return plain(report)


class ModesAnalysis(Analysis):
    name = "modes"
    summary = "The lowest natural frequencies and mode shapes about the equilibrium (or undeformed: at=undeformed)"
    long = True
    Options = ModesOptions
    Result = ModesReport

    def report(self, mech: Mechanism, newton: NewtonOptions, options: ModesOptions) -> dict[str, Any]:
        return modes_analysis_report(mech, newton, options)


MODES = ModesAnalysis()
