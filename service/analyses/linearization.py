"""The linearization analysis: the tangent stiffness K_T (and the seed-000 terms I-III where
they apply) at the equilibrium under the document's loads, or undeformed; with `state_space`,
also the linear model for controllers there: M, damping, K and the state space (A, B, C, D)
from chosen inputs to chosen outputs (service.vibration.state_space)."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from flexmech.models import Mechanism, MechanismError
from flexmech.service.analyses.base import Analysis, AnalysisOptions, AnalysisResult, ReportSize, state_numbers
from flexmech.service.analyses.shared_options import MAX_NAMES, Names
from flexmech.service.requests import under
from flexmech.service.solvers.equilibrium import solve_equilibrium
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.reports import coordinate_units, output_units, plain, stiffness_dict
from flexmech.service.vibration.frf import Damping
from flexmech.service.vibration.state_space import default_inputs, default_outputs, state_space_model


def linearization_report(
    mech: Mechanism, options: NewtonOptions, at: str = "equilibrium", state_space: StateSpaceOptions | None = None
) -> dict:
    """K_T and its terms at the equilibrium under the document's loads (or undeformed), and the
    state space if asked."""
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
    try:
        report["stiffness"] = stiffness_dict(mech, z)
    except MechanismError as exc:
        if state_space is None:
            raise
        # pins and sliders make K_T over the bodies' coordinates infinite; the modes' coordinates keep them
        report.setdefault("warnings", []).append(f"no tangent stiffness over the bodies' coordinates: {exc.problem}")
    if state_space is not None:
        report["state_space"] = _state_space(mech, z, state_space)
    return plain(report)


def _state_space(mech: Mechanism, z: Any, asked: StateSpaceOptions) -> dict[str, Any]:
    damping = Damping(asked.damping_ratio, asked.mass_damping, asked.stiffness_damping)
    return state_space_model(mech, z, asked.inputs, asked.outputs, damping, asked.modes).to_dict()


class StateSpaceOptions(BaseModel):
    """The linear model asked of the linearization (service.vibration.state_space)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    inputs: Names | None = Field(
        None,
        min_length=1,
        max_length=MAX_NAMES,
        description="the inputs, one document unit each: load components (JSON pointers; default: every "
        "force and moment component of the document's loads)",
        examples=[["/loads/hold/force/1"]],
    )
    outputs: Names | None = Field(
        None,
        min_length=1,
        max_length=MAX_NAMES,
        description="the outputs (names as in a solve's outputs; default: the positions and rotations among the "
        "document's named outputs, else every free body coordinate)",
        examples=[["bodies.tip.y"]],
    )
    modes: int | None = Field(
        None, ge=1, description="keep the lowest modes (default: every one); D takes the static response of the rest"
    )
    damping_ratio: float = Field(0.0, ge=0, lt=1, description="modal damping ratio zeta on every mode")
    mass_damping: float = Field(
        0.0, ge=0, description="Rayleigh's alpha (damping = alpha M + beta K)", json_schema_extra={"unit": "1/s"}
    )
    stiffness_damping: float = Field(0.0, ge=0, description="Rayleigh's beta", json_schema_extra={"unit": "s"})


class LinearizationOptions(AnalysisOptions):
    at: Literal["equilibrium", "undeformed"] = Field(
        "equilibrium", description="the state: the equilibrium under the document's loads, or undeformed"
    )
    state_space: StateSpaceOptions | None = Field(
        None,
        description="also the linear model there: M, damping and K over the modes' coordinates and the state space "
        "(A, B, C, D) over the modal coordinates and their rates, from these inputs to these outputs",
    )


class LinearizationReport(AnalysisResult):
    at: str
    stiffness: dict | None = Field(None, description="K_T, its terms, the units of its rows and columns")
    state_space: dict | None = Field(
        None,
        description="A, B, C, D, M, damping, K, G, shapes; the names and units of the states, inputs, outputs and "
        "coordinates; the poles (rad/s), each mode's frequency (Hz) and damping ratio, the static gain",
    )


class LinearizationAnalysis(Analysis):
    name = "linearization"
    summary = "The tangent stiffness K_T at the equilibrium (or undeformed: at=undeformed), in document units"
    Options = LinearizationOptions
    Result = LinearizationReport

    def report(self, mech: Mechanism, newton: NewtonOptions, options: LinearizationOptions) -> dict:
        return linearization_report(mech, newton, options.at, options.state_space)

    def report_size(self, mech: Mechanism, options: LinearizationOptions) -> ReportSize:
        """K_T and its terms; with a state space, A, B, C, D over the kept modes' states, and M,
        damping, K, G and the shapes over the modal coordinates (at most the unknowns)."""
        body = mech.n_body_coordinates
        numbers = state_numbers(mech) + 4 * body * body
        asked = options.state_space
        if asked is None:
            return ReportSize(numbers, f"K_T and its terms over {body} coordinates", "/document", "")
        n = mech.n_free
        kept = min(asked.modes or n, n)
        states = 2 * kept
        inputs = len(asked.inputs) if asked.inputs is not None else len(default_inputs(mech))
        outputs = len(asked.outputs) if asked.outputs is not None else len(default_outputs(mech))
        numbers += (states + outputs) * (states + inputs) + 4 * n * n + n * kept + outputs * inputs + 8 * kept
        return ReportSize(
            numbers,
            f"a state space of {states} states, {inputs} inputs, {outputs} outputs over {n} coordinates",
            "/state_space/outputs" if outputs >= inputs else "/state_space/inputs",
            "name fewer outputs or inputs, or keep fewer modes (state_space.modes)",
        )


LINEARIZATION = LinearizationAnalysis()
