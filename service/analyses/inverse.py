"""The inverse analysis: the wrench each body needs (loads plus supports) to hold given body
displacements, in closed form (elements whose forces follow from the body motions)."""

from __future__ import annotations

from typing import Any

from models import Mechanism
from service.analyses.base import Analysis, AnalysisRequest
from service.inverse import inverse_wrenches
from service.reports import plain


def inverse_report(mech: Mechanism, displacements: dict[str, Any]) -> dict:
    """The wrench each body needs (loads plus supports) to hold the given body displacements
    [dx, dy, rotation] in document units; bodies not named stay where they are."""
    wrenches = inverse_wrenches(mech, {k: tuple(v) for k, v in displacements.items()})
    force, moment = mech.doc_unit("force"), mech.doc_unit("moment")
    return plain({
        "analysis": "inverse", "name": mech.document.name, "status": "converged", "message": "",
        "wrenches": {b: {"Fx": w[0], "Fy": w[1], "M": w[2]} for b, w in wrenches.items()},
        "wrench_units": {"Fx": force, "Fy": force, "M": moment},
    })


class InverseAnalysis(Analysis):
    name = "inverse"
    summary = "The wrench each body needs to hold given body displacements (closed form, no iteration)"

    def run(self, mech: Mechanism, request: AnalysisRequest) -> dict:
        return inverse_report(mech, request.get("displacements", {}))


INVERSE = InverseAnalysis()
