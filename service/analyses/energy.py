"""The energy analysis: the equilibrium as the minimum of the total potential, by IPOPT
(mechanisms whose elements all have an energy form: rigid bodies, springs, pins, sliders)."""

from __future__ import annotations

import numpy as np
from pydantic import Field

from flexmech.models import Mechanism, MechanismError
from flexmech.service.analyses.base import Analysis, AnalysisOptions, ReportSize
from flexmech.service.analyses.equilibrium import EquilibriumReport, solution_report, solution_size
from flexmech.service.requests import under
from flexmech.service.solvers.energy import minimize_energy
from flexmech.service.solvers.equilibrium import EquilibriumResult
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.reports import plain, stiffness_dict


class EnergyOptions(AnalysisOptions):
    stiffness: bool = Field(False, description="also return the tangent stiffness K_T at the minimum")


class EnergyAnalysis(Analysis):
    name = "energy"
    summary = (
        "The minimum of the total potential (strain energy less the work of dead loads) under the "
        "joints' constraints, by IPOPT; the same report as equilibrium"
    )
    sweepable = True
    Options = EnergyOptions
    Result = EquilibriumReport

    def report(self, mech: Mechanism, newton: NewtonOptions, options: EnergyOptions) -> dict:
        try:
            result = minimize_energy(mech, newton)
        except MechanismError as exc:
            raise under("/document", exc) from None
        report = solution_report(mech, result, self.name)
        if options.stiffness and result.converged:
            report["stiffness"] = stiffness_dict(mech, result.z)
        return plain(report)

    def report_size(self, mech: Mechanism, options: EnergyOptions) -> ReportSize:
        return solution_size(mech, options.stiffness, None)

    def point(self, mech: Mechanism, p: np.ndarray, guess: np.ndarray, options: NewtonOptions) -> EquilibriumResult:
        return minimize_energy(mech, options, mech.graphs.energy_form.x_of_state(guess), p)


ENERGY = EnergyAnalysis()
