"""The analyses /v1/solve, the CLI, the client, batch, the workbench and the sweep job take from
the registry: one module each, registered here (one line per analysis). A new analysis is a
new module and a line (or, outside the package, `ANALYSES.register(...)` in a plugin module
named by FLEXMECH_PLUGINS)."""

from flexmech.service.analyses.base import Analyses, Analysis, AnalysisOptions, AnalysisRequest, AnalysisResult
from flexmech.service.analyses.contact import CONTACT
from flexmech.service.analyses.energy import ENERGY
from flexmech.service.analyses.equilibrium import EQUILIBRIUM
from flexmech.service.analyses.frequency_response import FREQUENCY_RESPONSE
from flexmech.service.analyses.inverse import INVERSE
from flexmech.service.analyses.linearization import LINEARIZATION
from flexmech.service.analyses.modes import MODES
from flexmech.service.analyses.simulate import SIMULATE
from flexmech.service.analyses.tolerance import TOLERANCE
from flexmech.service.analyses.trace import TRACE

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
        TOLERANCE,
    ]
)

# Last: a plugin module registers on ANALYSES, which exists by now.
from flexmech.service.plugins import load_plugins  # noqa: E402

load_plugins()

__all__ = ["ANALYSES", "Analysis", "AnalysisOptions", "AnalysisRequest", "AnalysisResult"]
