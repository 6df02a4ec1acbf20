"""The equilibrium analysis: Newton under the document's loads, optionally for a target (the
value of a numeric field at which an output reaches a value, e.g. the closing force), with
the tangent stiffness and sensitivities at the solution."""

from __future__ import annotations

import numpy as np
from pydantic import Field

from flexmech.models import Mechanism, MechanismError
from flexmech.service.analyses.base import Analysis, AnalysisOptions, AnalysisResult, ReportSize, state_numbers
from flexmech.service.analyses.shared_options import Sensitivities, Target
from flexmech.service.requests import under
from flexmech.service.solvers.equilibrium import EquilibriumResult, newton, solve_equilibrium
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.reports import coordinate_units, output_units, plain, stiffness_dict
from flexmech.service.solvers.sweep import TargetResult, solve_for_target


def solution_report(mech: Mechanism, result: EquilibriumResult, analysis: str) -> dict:
    """Status, diagnostics, displacements and outputs of a state, in document units."""
    return {
        "analysis": analysis,
        "name": mech.document.name,
        **result.summary(),
        "history": result.history,
        "output_units": output_units(mech),
        "displacement_units": coordinate_units(mech),
    }


def solve_state(
    mech: Mechanism, options: NewtonOptions, target: Target | None
) -> tuple[EquilibriumResult, TargetResult | None]:
    """The equilibrium under the document's loads, or for a target; errors name the request's
    field (/target/... or /document/...)."""
    try:
        if target is None:
            return solve_equilibrium(mech, options), None
        try:
            mech.parameter_index(target.path)
        except MechanismError as exc:
            raise MechanismError("/target/path", exc.problem) from None
        if target.output not in mech.graphs.output_names:
            raise MechanismError("/target/output", f"unknown output '{target.output}'")
        found = solve_for_target(mech, target.path, target.output, target.equals, options)
        return found.equilibrium, found
    except MechanismError as exc:
        raise (exc if exc.pointer.startswith("/target") else under("/document", exc)) from None


def equilibrium_report(
    mech: Mechanism,
    options: NewtonOptions,
    stiffness: bool = False,
    target: Target | None = None,
    sensitivities: Sensitivities | None = None,
) -> dict:
    """Solve the equilibrium; status, diagnostics, displacements and outputs in document units.

    target: instead of the document's value of the numeric field
    `path`, find the value for which `output` equals `equals` (document units), e.g. the
    actuation force that closes a gripper; reported under "target".
    sensitivities: d(outputs)/d(parameters) at the solution (the
    target's field following), reported under "sensitivities"."""
    result, found = solve_state(mech, options, target)
    mech = result.mechanism
    report = solution_report(mech, result, "equilibrium")
    if found is not None and target is not None:
        report["target"] = {
            "path": target.path,
            "value": found.value,
            "status": found.status,
            "unit": mech.doc_unit(mech.parameter_kind(target.path)),
            "output": target.output,
            "equals": target.equals,
            "output_unit": report["output_units"].get(target.output, ""),
        }
    if stiffness and result.converged:
        report["stiffness"] = stiffness_dict(mech, result.z)
    if sensitivities is not None and result.converged:
        from flexmech.service.design.sensitivity import equilibrium_sensitivities

        try:
            following = (target.path, target.output) if target is not None else None
            report["sensitivities"] = equilibrium_sensitivities(
                mech, result.z, sensitivities.parameters, sensitivities.outputs, following
            ).to_dict()
        except MechanismError as exc:
            raise MechanismError("/sensitivities" + exc.pointer, exc.problem) from None
    return plain(report)


def solution_size(mech: Mechanism, stiffness: bool, sensitivities: Sensitivities | None) -> ReportSize:
    """A state's report with K_T (and its three terms) and sensitivities (values and units)."""
    body = mech.n_body_coordinates
    numbers, terms = state_numbers(mech), ["one state"]
    if stiffness:
        numbers += 4 * body * body
        terms.append(f"K_T and its terms over {body} coordinates")
    if sensitivities is not None:
        pairs = len(sensitivities.outputs) * len(sensitivities.parameters)
        numbers += 2 * pairs
        terms.append(f"{len(sensitivities.outputs)} outputs x {len(sensitivities.parameters)} parameters")
    return ReportSize(numbers, ", ".join(terms), "/sensitivities/outputs", "ask for fewer sensitivities")


class EquilibriumOptions(AnalysisOptions):
    target: Target | None = Field(
        None,
        description="solve for the field value that reaches a target (e.g. the actuation force that closes a gripper)",
        json_schema_extra={"document_default": "/sweep/until"},
    )
    stiffness: bool = Field(False, description="also return the tangent stiffness K_T at the solution")
    sensitivities: Sensitivities | None = Field(
        None, description="also return d(outputs)/d(parameters) by the implicit function theorem"
    )


class EquilibriumReport(AnalysisResult):
    iterations: int = 0
    displacements: dict[str, float | None] = Field(default_factory=dict)
    displacement_units: dict[str, str] = Field(default_factory=dict)
    outputs: dict[str, float | None] = Field(default_factory=dict)
    output_units: dict[str, str] = Field(default_factory=dict)
    target: dict | None = Field(None, description="path, value, unit, status of the target's field")
    stiffness: dict | None = None
    sensitivities: dict | None = None


class EquilibriumAnalysis(Analysis):
    name = "equilibrium"
    summary = (
        "Newton on the residual form under the document's loads; optionally for a target, with the "
        "tangent stiffness and sensitivities"
    )
    sweepable = True
    Options = EquilibriumOptions
    Result = EquilibriumReport

    def report(self, mech: Mechanism, newton: NewtonOptions, options: EquilibriumOptions) -> dict:
        return equilibrium_report(mech, newton, options.stiffness, options.target, options.sensitivities)

    def report_size(self, mech: Mechanism, options: EquilibriumOptions) -> ReportSize:
        return solution_size(mech, options.stiffness, options.sensitivities)

    def point(self, mech: Mechanism, p: np.ndarray, guess: np.ndarray, options: NewtonOptions) -> EquilibriumResult:
        return newton(mech, p, guess, options)


EQUILIBRIUM = EquilibriumAnalysis()
