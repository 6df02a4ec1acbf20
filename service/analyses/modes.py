"""The modes analysis: the lowest natural frequencies and mass-normalized mode shapes of a
mechanism about its equilibrium under the document's loads (prestress and load stiffness
included), or about the undeformed state (service.vibration)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, Field

from flexmech.models import Mechanism, MechanismError
from flexmech.service.analyses.base import Analysis, AnalysisOptions, AnalysisResult, ReportSize, drawn_numbers
from flexmech.service.analyses.shared_options import MAX_NAMES, Names
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.reports import plain
from flexmech.service.vibration.contact_state import contact_system
from flexmech.service.vibration.eigen import vibration_eigen
from flexmech.service.vibration.modes import MechanismModes, mechanism_modes
from flexmech.service.vibration.report import modes_report
from flexmech.service.vibration.sensitivity import frequency_sensitivities
from flexmech.service.vibration.state import vibration_state


class ModesOptions(AnalysisOptions):
    count: int = Field(6, ge=1, le=500, description="how many of the lowest modes")
    at: Literal["equilibrium", "undeformed", "contact"] = Field(
        "equilibrium",
        description="the state: the equilibrium under the document's loads, undeformed, or the contact "
        "state (the frictionless minimum under the document's contacts, its closed contacts held)",
    )
    shapes: bool = Field(True, description="report each mode's shape (bodies and the elements' mass points)")
    sensitivities: Names = Field(
        default_factory=list,
        max_length=MAX_NAMES,
        description="numeric fields (JSON pointers) to differentiate each frequency by, exactly",
        examples=[["/sections/rod/h"]],
    )


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
    sensitivities: dict[str, float | None] | None = Field(
        None, description="d frequency / d field, in Hz per the field's document unit"
    )


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
    lines: dict[str, list[list[float]]] = Field(
        default_factory=dict,
        description="each drawn element's centre line at the state (its modes' shape.lines move it)",
    )
    bodies: dict[str, dict[str, Any]] = Field(
        default_factory=dict,
        description="each body at the state: its reference point [x, y] (document length units; its modes' "
        "shape.bodies move it), whether it is fixed, and the element ends it carries [element, start | end]",
    )


def modes_analysis_report(mech: Mechanism, newton: NewtonOptions, options: ModesOptions) -> dict[str, Any]:
    report: dict[str, Any] = {"analysis": "modes", "name": mech.document.name, "at": options.at}
    if options.at == "contact":
        if options.sensitivities:
            raise MechanismError(
                "/sensitivities", "frequency derivatives are given about an equilibrium, not a contact state"
            )
        held = contact_system(mech, newton, report)
        if held is None:
            return plain(report)
        system, z = held
        found = MechanismModes(system, vibration_eigen(system.K, system.M, system.G, options.count))
    else:
        state = vibration_state(mech, newton, options.at, report)
        if state is None:
            return plain(report)
        z, found = state, mechanism_modes(mech, state, options.count)
    report.update(modes_report(mech, found, z, options.shapes))
    if options.sensitivities:
        _add_sensitivities(report, mech, z, found, options)
    unstable = [m["mode"] for m in report["modes"] if m["kind"] == "unstable"]
    if unstable:
        report.setdefault("warnings", []).append(
            f"the state is unstable: mode(s) {', '.join(map(str, unstable))} have omega^2 < 0"
        )
    return plain(report)


def _add_sensitivities(
    report: dict[str, Any], mech: Mechanism, z: np.ndarray | None, found: MechanismModes, options: ModesOptions
) -> None:
    slots = mech.parameter_indices(options.sensitivities, "/sensitivities")
    state = z if z is not None else np.zeros(mech.n_free)
    matrix, clusters = frequency_sensitivities(mech, state, found, slots, options.at == "equilibrium")
    for mode, row in zip(report["modes"], matrix):
        mode["sensitivities"] = dict(zip(options.sensitivities, row.tolist()))
    report["units"]["sensitivities"] = {
        path: f"Hz/{mech.doc_unit(mech.parameters[slot].kind)}" for path, slot in zip(options.sensitivities, slots)
    }
    for cluster in clusters:
        report.setdefault("warnings", []).append(
            f"modes {', '.join(str(k + 1) for k in cluster)} share one frequency: their derivatives are of their "
            "mean (a field splits repeated frequencies along directions of its own)"
        )


class ModesAnalysis(Analysis):
    name = "modes"
    summary = "The lowest natural frequencies and mode shapes about the equilibrium (or undeformed: at=undeformed)"
    long = True
    Options = ModesOptions
    Result = ModesReport
    figures = (
        ("plot", (".png", ".svg"), "Draw every mode's shape over the mechanism (elements and bodies), a panel each."),
        ("animation", (".gif",), "Animate the first mode through one period."),
    )

    def report(self, mech: Mechanism, newton: NewtonOptions, options: ModesOptions) -> dict[str, Any]:
        return modes_analysis_report(mech, newton, options)

    def report_size(self, mech: Mechanism, options: ModesOptions) -> ReportSize:
        """Per mode its figures (frequencies, effective masses, energy shares per element and
        body, sensitivities) and, with shapes, every coordinate and mass point and its centre
        lines; the drawn state once."""
        count = min(options.count, mech.n_free)
        owners = len(mech.document.elements) + len(mech.structure.bodies)
        per_mode = 12 + owners + len(options.sensitivities)
        drawn = drawn_numbers(mech)
        if options.shapes:
            per_mode += 3 * mech.n_free + drawn
        return ReportSize(
            count * per_mode + drawn,
            f"{count} modes x {per_mode} numbers",
            "/count",
            "ask for fewer modes, or leave out their shapes (shapes: false)",
        )

    def draw(
        self,
        mech: Mechanism,
        newton: NewtonOptions,
        options: ModesOptions,
        report: dict[str, Any],
        figure: str,
        path: Path,
    ) -> None:
        from flexmech.service.vibration.figures import animate_mode, plot_modes

        if figure == "plot":
            plot_modes(report, path, mech.doc_unit("length"))
        else:
            animate_mode(report, 1, path, mech.doc_unit("length"))


MODES = ModesAnalysis()
