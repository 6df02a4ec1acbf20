"""The tolerance analysis: how the document's `tolerances` (models.documents.tolerances) scatter
its responses (statics outputs and a target's field, a contact state's outputs, or natural
frequencies): first order from the exact sensitivities, each source's share ranked; Monte Carlo
of seeded samples; the yield against the specs (service.tolerances)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from pydantic import Field

from flexmech.models import Mechanism, MechanismError
from flexmech.service.analyses.base import Analysis, AnalysisOptions, AnalysisResult, ReportSize, state_numbers
from flexmech.service.analyses.shared_options import MAX_NAMES, Names
from flexmech.service.deadline import ends_after, passed
from flexmech.service.requests import under
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.reports import plain

if TYPE_CHECKING:
    from flexmech.service.tolerances.fields import Scatter
    from flexmech.service.tolerances.responses import Responses

MAX_SAMPLES = 100_000


class ToleranceOptions(AnalysisOptions):
    samples: int = Field(
        1000, ge=0, le=MAX_SAMPLES, description="Monte Carlo samples (0: first order only)", examples=[4000]
    )
    seed: int = Field(
        0, ge=0, le=2**32 - 1, description="the samples' random seed: a seed gives the same samples anywhere"
    )
    of: Literal["equilibrium", "contact", "modes"] = Field(
        "equilibrium",
        description="the responses: outputs at the equilibrium under the document's loads (and the tolerances' "
        "target), at the contact state, or the lowest natural frequencies (frequency.1, ...)",
    )
    outputs: Names | None = Field(
        None,
        min_length=1,
        max_length=MAX_NAMES,
        description="the outputs to follow (default: the document's named outputs; modes: frequency.1 ... of `count`)",
        examples=[["end_effector.x"]],
    )
    count: int = Field(3, ge=1, le=50, description="modes: how many of the lowest frequencies")


class ToleranceReport(AnalysisResult):
    of: str
    samples: int = Field(description="Monte Carlo samples run")
    seed: int
    fields: list[dict[str, Any]] = Field(
        description="each toleranced field: path, value, distribution, width, std, unit"
    )
    sources: list[str] = Field(description="the independent sources, each named by its leading field")
    responses: dict[str, dict[str, Any]] = Field(
        description="per response: unit, nominal, first_order (mean, std, contributions ranked), linearity (the "
        "curvature's mean shift, near_linear and why), monte_carlo (mean, std, their standard errors, percentiles, "
        "histogram, agreement with first order), spec"
    )
    yield_: dict[str, Any] | None = Field(
        None,
        alias="yield",
        description="the share of samples meeting every spec (Monte Carlo, its standard error; and first order on "
        "the same samples), the failing samples' fields",
    )


class ToleranceAnalysis(Analysis):
    name = "tolerance"
    summary = (
        "How the document's tolerances scatter its responses: first order from exact sensitivities (each field's "
        "share ranked), Monte Carlo of seeded samples, and the yield against the specs"
    )
    long = True
    Options = ToleranceOptions
    Result = ToleranceReport
    figures = (("plot", (".png", ".svg", ".pdf"), "histograms of the samples and each field's contribution"),)

    def report(self, mech: Mechanism, newton: NewtonOptions, options: ToleranceOptions) -> dict[str, Any]:
        from flexmech.service.tolerances.fields import resolve_scatter
        from flexmech.service.tolerances.report import spec_bounds, tolerance_report

        spec = mech.document.tolerances
        if spec is None:
            raise MechanismError(
                "/document/tolerances", "the document has no tolerances section: give the fields' scatter"
            )
        end = ends_after(newton.time_limit)
        try:
            scatter = resolve_scatter(mech, spec)
            responses = responses_of(mech, scatter, options, newton)
            specs = spec_bounds(mech, spec, responses)
        except MechanismError as exc:
            raise (exc if exc.pointer.startswith(("/outputs", "/count")) else under("/document", exc)) from None
        body = tolerance_report(mech, scatter, responses, specs, options.samples, options.seed, lambda: passed(end))
        stopped = body["samples"] < options.samples
        status, message = "converged", ""
        if stopped:
            status = "time_limit"
            message = (
                f"{body['samples']} of {options.samples} samples within the time limit of {newton.time_limit:g} s "
                "(an analysis job has more time)"
            )
        head = {
            "analysis": self.name,
            "name": mech.document.name,
            "status": status,
            "message": message,
            "of": options.of,
        }
        out: dict[str, Any] = plain({**head, **body})
        return out

    def report_size(self, mech: Mechanism, options: ToleranceOptions) -> ReportSize:
        """Per response its statistics and histogram, and at most 50 failing samples' fields."""
        spec = mech.document.tolerances
        fields = len(spec.fields) if spec is not None else 0
        responses = len(options.outputs) if options.outputs is not None else len(mech.graphs.output_names) + 1
        if options.of == "modes":
            responses = options.count
        numbers = state_numbers(mech) + responses * (80 + 4 * fields) + 50 * (fields + 1)
        return ReportSize(numbers, f"{responses} responses x {fields} fields", "/outputs", "follow fewer outputs")

    def draw(
        self, mech: Mechanism, newton: NewtonOptions, options: Any, report: dict[str, Any], figure: str, path: Path
    ) -> None:
        from flexmech.service.tolerances.plots import tolerance_figure

        tolerance_figure(report, path)


def responses_of(mech: Mechanism, scatter: Scatter, options: ToleranceOptions, newton: NewtonOptions) -> Responses:
    """The responses the options ask for (service.tolerances.statics; .states for contact and modes)."""
    target = mech.document.tolerances.target if mech.document.tolerances is not None else None
    if options.of == "equilibrium":
        from flexmech.service.tolerances.statics import statics_responses

        return statics_responses(mech, scatter, options.outputs, target, newton)
    if target is not None:
        raise MechanismError("/tolerances/target", f"a target is solved for in statics only, not with of={options.of}")
    if options.of == "modes":
        from flexmech.service.analyses.base import AnalysisRequest
        from flexmech.service.analyses.modes import MODES
        from flexmech.service.tolerances.states import modes_responses

        def run_modes(sample: Mechanism, settings: dict[str, Any]) -> dict[str, Any]:
            return MODES.run(sample, AnalysisRequest(newton, settings))

        return modes_responses(mech, scatter, options.outputs, options.count, run_modes)
    from flexmech.service.tolerances.states import contact_responses

    return contact_responses(mech, scatter, options.outputs, newton)


TOLERANCE = ToleranceAnalysis()
