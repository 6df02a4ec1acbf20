"""The energy analysis: the equilibrium as the minimum of the total potential, by IPOPT
(mechanisms whose elements all have an energy form: rigid bodies, springs, pins, sliders)."""

from __future__ import annotations

import numpy as np

from models import Mechanism, MechanismError
from service.analyses.base import Analysis, AnalysisRequest
from service.analyses.equilibrium import solution_report
from service.energy import minimize_energy
from service.equilibrium import EquilibriumResult
from service.newton import NewtonOptions
from service.reports import plain, stiffness_dict
from service.requests import under


class EnergyAnalysis(Analysis):
    name = "energy"
    summary = ("The minimum of the total potential (strain energy less the work of dead loads) under the "
               "joints' constraints, by IPOPT; the same report as equilibrium")
    sweepable = True

    def run(self, mech: Mechanism, request: AnalysisRequest) -> dict:
        try:
            result = minimize_energy(mech, request.options)
        except MechanismError as exc:
            raise under("/document", exc) from None
        report = solution_report(mech, result, self.name)
        if request.get("stiffness", False) and result.converged:
            report["stiffness"] = stiffness_dict(mech, result.z)
        return plain(report)

    def point(self, mech: Mechanism, p: np.ndarray, guess: np.ndarray, options: NewtonOptions) -> EquilibriumResult:
        return minimize_energy(mech, options, mech.graphs.energy_form.x_of_state(guess), p)


ENERGY = EnergyAnalysis()
