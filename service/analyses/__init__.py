"""The analyses /v1/solve, the CLI and the sweep job dispatch through: one module each,
registered here (one line per analysis). A new analysis is a new module and a line."""

from service.analyses.base import Analyses, Analysis, AnalysisRequest
from service.analyses.contact import CONTACT
from service.analyses.energy import ENERGY
from service.analyses.equilibrium import EQUILIBRIUM
from service.analyses.inverse import INVERSE
from service.analyses.linearization import LINEARIZATION
from service.analyses.simulate import SIMULATE
from service.analyses.trace import TRACE

ANALYSES = Analyses([
    EQUILIBRIUM,
    LINEARIZATION,
    TRACE,
    INVERSE,
    ENERGY,
    CONTACT,
    SIMULATE,
])

__all__ = ["ANALYSES", "Analysis", "AnalysisRequest"]
