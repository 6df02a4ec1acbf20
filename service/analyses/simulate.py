"""The simulate analysis: a time simulation of the mechanism (service.dynamics) by its
document's `simulate` section, with the request's `simulate` fields over it. Answered in one
response, so its steps are bounded (SYNC_STEPS)."""

from __future__ import annotations

from models import Mechanism
from models.simulation_spec import IMPACT_SCHEMES
from service.analyses.base import Analysis, AnalysisRequest
from service.deadline import ends_after, passed
from service.dynamics.run import run_simulation, simulation_spec
from service.impacts.run import run_impacts
from service.reports import plain

SYNC_STEPS = 20_000
SYNC_IMPACT_STEPS = 2_000_000  # a microsecond each: a few seconds of a compiled impact model
SYNC_KEPT = 100_000  # states in one response (about 25 numbers each)
SYNC_IMPACT_BYTES = 192 * 2**20  # the memory one run's states may take in a solver worker


class SimulateAnalysis(Analysis):
    name = "simulate"
    summary = ("Motion in time: Newmark or generalized-alpha steps of the links' and bodies' dynamics under loads "
               "and prescribed motions in time; outputs, constraint forces and the energy balance per step; rigid bodies with "
               "contact impacts and friction (event-driven or Moreau-Jean)")

    def run(self, mech: Mechanism, request: AnalysisRequest) -> dict:
        spec = simulation_spec(mech, request.get("simulate", {}))
        limit = request.options.time_limit
        end = ends_after(limit)
        stop = (lambda: passed(end)) if limit else None
        if spec.scheme in IMPACT_SCHEMES:
            _, report = run_impacts(mech.document, spec, stop=stop, max_steps=SYNC_IMPACT_STEPS, max_kept=SYNC_KEPT,
                                    max_bytes=SYNC_IMPACT_BYTES)
        else:
            _, report = run_simulation(mech, spec, stop=stop, max_steps=SYNC_STEPS)
        if report["status"] == "stopped":
            report["status"] = "time_limit"
            report["message"] += f" (the time limit of {limit:g} s; a simulation job has more time)"
        return plain(report)


SIMULATE = SimulateAnalysis()
