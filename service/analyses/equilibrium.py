"""The equilibrium analysis: Newton under the document's loads, optionally for a target (the
value of a numeric field at which an output reaches a value, e.g. the closing force), with
the tangent stiffness and sensitivities at the solution."""

from __future__ import annotations

import numpy as np

from models import Mechanism, MechanismError
from service.analyses.base import Analysis, AnalysisRequest
from service.equilibrium import EquilibriumResult, newton, solve_equilibrium
from service.newton import NewtonOptions
from service.reports import coordinate_units, output_units, plain, stiffness_dict
from service.requests import under
from service.sweep import TargetResult, solve_for_target


def solution_report(mech: Mechanism, result: EquilibriumResult, analysis: str) -> dict:
    """Status, diagnostics, displacements and outputs of a state, in document units."""
    return {"analysis": analysis, "name": mech.document.name, **result.summary(), "history": result.history,
            "output_units": output_units(mech), "displacement_units": coordinate_units(mech)}


def solve_state(mech: Mechanism, options: NewtonOptions, target: dict | None) -> tuple[EquilibriumResult, TargetResult | None]:
    """The equilibrium under the document's loads, or for a target {path, output, equals};
    errors name the request's field (/target/... or /document/...)."""
    try:
        if target is None:
            return solve_equilibrium(mech, options), None
        try:
            mech.parameter_index(target["path"])
        except MechanismError as exc:
            raise MechanismError("/target/path", exc.problem) from None
        if target["output"] not in mech.graphs.output_names:
            raise MechanismError("/target/output", f"unknown output '{target['output']}'")
        found = solve_for_target(mech, target["path"], target["output"], float(target["equals"]), options)
        return found.equilibrium, found
    except MechanismError as exc:
        raise (exc if exc.pointer.startswith("/target") else under("/document", exc)) from None


def equilibrium_report(mech: Mechanism, options: NewtonOptions, stiffness: bool = False,
                       target: dict | None = None, sensitivities: dict | None = None) -> dict:
    """Solve the equilibrium; status, diagnostics, displacements and outputs in document units.

    target = {path, output, equals}: instead of the document's value of the numeric field
    `path`, find the value for which `output` equals `equals` (document units), e.g. the
    actuation force that closes a gripper; reported under "target".
    sensitivities = {parameters, outputs}: d(outputs)/d(parameters) at the solution (the
    target's field following), reported under "sensitivities"."""
    result, found = solve_state(mech, options, target)
    mech = result.mechanism
    report = solution_report(mech, result, "equilibrium")
    if found is not None:
        report["target"] = {"path": target["path"], "value": found.value, "status": found.status,
                            "unit": mech.doc_unit(mech.parameter_kind(target["path"]))}
    if stiffness and result.converged:
        report["stiffness"] = stiffness_dict(mech, result.z)
    if sensitivities is not None and result.converged:
        from service.sensitivity import equilibrium_sensitivities

        try:
            following = (target["path"], target["output"]) if target is not None else None
            report["sensitivities"] = equilibrium_sensitivities(
                mech, result.z, sensitivities["parameters"], sensitivities["outputs"], following).to_dict()
        except MechanismError as exc:
            raise MechanismError("/sensitivities" + exc.pointer, exc.problem) from None
    return plain(report)


class EquilibriumAnalysis(Analysis):
    name = "equilibrium"
    summary = ("Newton on the residual form under the document's loads; optionally for a target, with the "
               "tangent stiffness and sensitivities")
    sweepable = True

    def run(self, mech: Mechanism, request: AnalysisRequest) -> dict:
        return equilibrium_report(mech, request.options, bool(request.get("stiffness", False)),
                                  request.get("target"), request.get("sensitivities"))

    def point(self, mech: Mechanism, p: np.ndarray, guess: np.ndarray, options: NewtonOptions) -> EquilibriumResult:
        return newton(mech, p, guess, options)


EQUILIBRIUM = EquilibriumAnalysis()
