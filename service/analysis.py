"""Single analyses as plain data: what /v1/solve answers, what `flexmech solve` prints and what
`flexmech batch` writes. One call, dispatched through the registry (service.analyses).

Each analysis takes a compiled mechanism and returns a JSON-able dict in the document's units.
Every problem with the input raises MechanismError whose pointer is relative to the request
(the document's fields under /document), so the HTTP layer and the CLI report the same field.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from flexmech.models import Mechanism
from flexmech.service.analyses import ANALYSES, AnalysisOptions, AnalysisRequest
from flexmech.service.analyses.equilibrium import equilibrium_report
from flexmech.service.analyses.inverse import inverse_report
from flexmech.service.analyses.linearization import linearization_report
from flexmech.service.requests import Limits, compile_request, escape_pointer_part, newton_options, under
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.reports import coordinate_units, output_units, plain, stiffness_dict


def run_analysis(
    mech: Mechanism, name: str, options: NewtonOptions, given: AnalysisOptions | Mapping[str, Any] | None = None
) -> dict:
    """The report of analysis `name` (MechanismError at /analysis when there is none) under its
    options (typed, or a mapping checked into them)."""
    return ANALYSES.named(name).run(mech, AnalysisRequest(options, given))


__all__ = [
    "Limits",
    "compile_request",
    "coordinate_units",
    "equilibrium_report",
    "escape_pointer_part",
    "inverse_report",
    "linearization_report",
    "newton_options",
    "output_units",
    "plain",
    "run_analysis",
    "stiffness_dict",
    "under",
]
