"""The frequency_response analysis: amplitude and phase of chosen outputs under a harmonic input
(one component of a document load or of a prescribed displacement, its amplitude one document
unit) over a frequency range,
about the equilibrium under the document's loads or the undeformed state, with a modal damping
ratio and Rayleigh's mass and stiffness terms; each resonance's peak and half-power bandwidth
(service.vibration.frf)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, Field, ValidationInfo, field_validator

from flexmech.models import Mechanism, MechanismError
from flexmech.models.documents.fields import Pointer
from flexmech.service.analyses.base import Analysis, AnalysisOptions, AnalysisResult, ReportSize
from flexmech.service.analyses.shared_options import MAX_NAMES, Names
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.reports import plain
from flexmech.service.vibration.eigen import vibration_eigen
from flexmech.service.vibration.frf import RESONANCE_POINTS, TWO_PI, Damping, frequency_grid, modal_response, resonances
from flexmech.service.vibration.harmonic import channel
from flexmech.service.vibration.modes import modal_system
from flexmech.service.vibration.state import vibration_state


class FrequencyResponseOptions(AnalysisOptions):
    input: Pointer = Field(
        description="the harmonic input, amplitude one document unit: a load's component or a prescribed "
        "displacement's (JSON pointer)",
        examples=["/loads/actuation/force/1"],
    )
    outputs: Names = Field(
        min_length=1,
        max_length=MAX_NAMES,
        description="the outputs to watch (names as in a solve's outputs; each once)",
        examples=[["bodies.input.y"]],
    )
    start: float | None = Field(
        None,
        gt=0,
        description="lowest frequency (default: a tenth of the first elastic mode's)",
        json_schema_extra={"unit": "Hz"},
    )
    stop: float | None = Field(
        None,
        gt=0,
        description="highest frequency (default: twice the sixth mode's, or the highest)",
        json_schema_extra={"unit": "Hz"},
    )
    points: int = Field(400, ge=2, le=100_000, description="log-spaced frequencies (more are added at each resonance)")
    damping_ratio: float = Field(0.01, ge=0, lt=1, description="modal damping ratio zeta on every mode")
    mass_damping: float = Field(
        0.0, ge=0, description="Rayleigh's alpha (D = alpha M + beta K)", json_schema_extra={"unit": "1/s"}
    )
    stiffness_damping: float = Field(0.0, ge=0, description="Rayleigh's beta", json_schema_extra={"unit": "s"})
    at: Literal["equilibrium", "undeformed"] = Field(
        "equilibrium", description="the state: the equilibrium under the document's loads, or undeformed"
    )

    @field_validator("stop")
    @classmethod
    def _range(cls, stop: float | None, info: ValidationInfo) -> float | None:
        start = info.data.get("start")
        if stop is not None and start is not None and stop <= start:
            raise ValueError(f"the range is empty: stop ({stop:g} Hz) must exceed start ({start:g} Hz)")
        return stop


class Response(BaseModel):
    unit: str = Field(description="output unit per input unit")
    amplitude: list[float | None] = Field(description="None where undamped and exactly at a natural frequency")
    phase: list[float | None] = Field(description="degrees, of the output behind the input")
    static: float | None = Field(description="the response at zero frequency (None with a rigid mode)")


class Resonance(BaseModel):
    mode: int
    output: str
    frequency: float = Field(description="Hz, of the peak")
    amplitude: float
    phase: float
    bandwidth: float | None = Field(description="Hz, between the half-power points")
    quality: float | None = Field(description="frequency / bandwidth")


class FrequencyResponseReport(AnalysisResult):
    at: str
    input: str = Field(description="the field whose harmonic motion or force drives the response")
    frequencies: list[float] = Field(default_factory=list, description="Hz")
    responses: dict[str, Response] = Field(default_factory=dict)
    resonances: list[Resonance] = Field(default_factory=list)
    natural_frequencies: list[float | None] = Field(default_factory=list, description="Hz, of every mode")


def frequency_response_report(
    mech: Mechanism, newton: NewtonOptions, options: FrequencyResponseOptions
) -> dict[str, Any]:
    report: dict[str, Any] = {
        "analysis": "frequency_response",
        "name": mech.document.name,
        "at": options.at,
        "input": options.input,
    }
    z = vibration_state(mech, newton, options.at, report)
    if z is None:
        return plain(report)
    system = modal_system(mech, z)
    eigen = vibration_eigen(system.K, system.M, system.G, None)  # every mode: the superposition is exact
    link = channel(mech, z, system, options.input, options.outputs)
    damping = Damping(options.damping_ratio, options.mass_damping, options.stiffness_damping)
    response = modal_response(eigen, link.outputs, link.force, damping, link.inertial, link.direct, link.carried)
    start, stop = _range(options, eigen.omega_squared, eigen.kinds)
    natural = [
        math.sqrt(v) / TWO_PI if kind == "elastic" else None for v, kind in zip(eigen.omega_squared, eigen.kinds)
    ]
    zetas = [(f, c / (2 * f * TWO_PI)) for f, c in zip(natural, response.rates) if f]
    f = frequency_grid(start, stop, options.points, zetas)
    H = response.at(TWO_PI * f) * link.scale[:, None]
    static = response.static()
    report["frequencies"] = f
    report["responses"] = {
        name: {
            "unit": f"{unit}/{link.input_unit}",
            "amplitude": np.abs(row),
            "phase": np.degrees(np.angle(row)),
            "static": None if static is None else float(static[i] * link.scale[i]),
        }
        for i, (name, unit, row) in enumerate(zip(options.outputs, link.output_units, H))
    }
    peaks = resonances(response, eigen.kinds, start, stop)
    report["resonances"] = [
        {**peak, "output": options.outputs[peak["output"]], "amplitude": peak["amplitude"] * link.scale[peak["output"]]}
        for peak in peaks
    ]
    report["natural_frequencies"] = natural
    if not damping.any:
        report.setdefault("warnings", []).append("undamped: the response is unbounded at each natural frequency")
    return plain(report)


def _range(options: FrequencyResponseOptions, values: np.ndarray, kinds: list[str]) -> tuple[float, float]:
    elastic = [math.sqrt(v) / TWO_PI for v, kind in zip(values, kinds) if kind == "elastic"]
    start = options.start if options.start is not None else (elastic[0] / 10 if elastic else 0.1)
    stop = options.stop if options.stop is not None else 2 * (elastic[min(5, len(elastic) - 1)] if elastic else 1.0)
    if stop <= start:
        raise MechanismError("/stop", f"the range is empty: stop ({stop:g} Hz) must exceed start ({start:g} Hz)")
    return start, stop


class FrequencyResponseAnalysis(Analysis):
    name = "frequency_response"
    summary = "Amplitude and phase of outputs under a harmonic load over a frequency range, with resonance peaks"
    long = True
    Options = FrequencyResponseOptions
    Result = FrequencyResponseReport
    aliases = ("frf",)
    figures = (("plot", (".png", ".svg"), "Draw the Bode plot: amplitude and phase of the outputs."),)

    def report(self, mech: Mechanism, newton: NewtonOptions, options: FrequencyResponseOptions) -> dict[str, Any]:
        return frequency_response_report(mech, newton, options)

    def report_size(self, mech: Mechanism, options: FrequencyResponseOptions) -> ReportSize:
        """Amplitude and phase per output and frequency: the asked points and up to
        RESONANCE_POINTS more across each mode's resonance; each mode's peaks per output."""
        modes, outputs = mech.n_free, len(options.outputs)
        frequencies = options.points + RESONANCE_POINTS * modes
        numbers = 2 * outputs * frequencies + frequencies + modes * (1 + 7 * outputs)
        pointer = "/outputs" if outputs > options.points else "/points"
        return ReportSize(
            numbers,
            f"{outputs} outputs x {frequencies} frequencies x 2 (amplitude, phase)",
            pointer,
            "use fewer points or outputs",
        )

    def draw(
        self,
        mech: Mechanism,
        newton: NewtonOptions,
        options: FrequencyResponseOptions,
        report: dict[str, Any],
        figure: str,
        path: Path,
    ) -> None:
        from flexmech.service.vibration.figures import plot_bode

        plot_bode(report, path)


FREQUENCY_RESPONSE = FrequencyResponseAnalysis()
