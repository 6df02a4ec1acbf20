"""The inverse analysis: the wrench each body needs (loads plus supports) to hold given body
displacements, in closed form (elements whose forces follow from the body motions)."""

from __future__ import annotations

from typing import Any

from pydantic import Field

from flexmech.models import Mechanism
from flexmech.models.documents.fields import Name
from flexmech.service.analyses.base import Analysis, AnalysisOptions, AnalysisResult
from flexmech.service.solvers.inverse import inverse_wrenches
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.reports import plain


def inverse_report(mech: Mechanism, displacements: dict[str, Any]) -> dict:
    """The wrench each body needs (loads plus supports) to hold the given body displacements
    [dx, dy, rotation] in document units; bodies not named stay where they are."""
    wrenches = inverse_wrenches(mech, {k: tuple(v) for k, v in displacements.items()})
    force, moment = mech.doc_unit("force"), mech.doc_unit("moment")
    return plain(
        {
            "analysis": "inverse",
            "name": mech.document.name,
            "status": "converged",
            "message": "",
            "wrenches": {b: {"Fx": w[0], "Fy": w[1], "M": w[2]} for b, w in wrenches.items()},
            "wrench_units": {"Fx": force, "Fy": force, "M": moment},
        }
    )


class InverseOptions(AnalysisOptions):
    displacements: dict[Name, tuple[float, float, float]] = Field(
        description="[dx, dy, rotation] of bodies (document units); bodies not named stay put",
        examples=[{"input": [0.001, 0, 0]}],
    )


class InverseReport(AnalysisResult):
    wrenches: dict[str, dict[str, float | None]] = Field(description="per body its Fx, Fy, M")
    wrench_units: dict[str, str]


class InverseAnalysis(Analysis):
    name = "inverse"
    summary = "The wrench each body needs to hold given body displacements (closed form, no iteration)"
    Options = InverseOptions
    Result = InverseReport

    def report(self, mech: Mechanism, newton: NewtonOptions, options: InverseOptions) -> dict:
        return inverse_report(mech, options.displacements)


INVERSE = InverseAnalysis()
