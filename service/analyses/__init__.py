"""The analyses /v1/solve, the CLI, the client, batch, the workbench and the sweep job take from
the registry: one module each, registered here (one line per analysis). A new analysis is a
new module and a line (or, outside the package, `ANALYSES.register(...)` in a plugin module
named by FLEXMECH_PLUGINS)."""

from service.analyses.base import Analyses, Analysis, AnalysisOptions, AnalysisRequest, AnalysisResult
from service.analyses.contact import CONTACT
from service.analyses.energy import ENERGY
from service.analyses.equilibrium import EQUILIBRIUM
from service.analyses.frequency_response import FREQUENCY_RESPONSE
from service.analyses.inverse import INVERSE
from service.analyses.linearization import LINEARIZATION
from service.analyses.modes import MODES
from service.analyses.simulate import SIMULATE
from service.analyses.trace import TRACE

ANALYSES = Analyses(
    [
        EQUILIBRIUM,
        LINEARIZATION,
        TRACE,
        INVERSE,
        ENERGY,
        CONTACT,
        SIMULATE,
        MODES,
        FREQUENCY_RESPONSE,
    ]
)

# Last: a plugin module registers on ANALYSES, which exists by now.
from service.plugins import load_plugins  # noqa: E402

load_plugins()

__all__ = ["ANALYSES", "Analysis", "AnalysisOptions", "AnalysisRequest", "AnalysisResult"]
