"""What the command line names before it imports any physics: the choices its help lists and
the registry's built-in analyses, so that `flexmech --help` and a command's --help answer
without NumPy, CasADi or the models (issue 28: under 0.5 s; benchmarks/cli_startup.py).

Each name here is a copy of its source's, which stays the one that is checked against when a
command runs; tests/interfaces/test_cli_polish.py holds every copy equal to its source. When
the registry is imported already, or plugins are named (they register on it), the registry
itself answers (loaded_registry)."""

from __future__ import annotations

import sys
from collections.abc import Collection, Iterable
from typing import TYPE_CHECKING

from flexmech.service.plugins import plugin_names

if TYPE_CHECKING:
    from flexmech.service.analyses.base import Analyses

# models.MODELS and models.COMPARED_MODELS (the curved beams' models)
MODEL_NAMES = ("linear", "partial_nonlinear", "exact", "conservative")
COMPARED_MODEL_NAMES = MODEL_NAMES[:3]

# service.analyses: the built-in analyses in the registry's order ...
ANALYSIS_NAMES = (
    "equilibrium",
    "linearization",
    "trace",
    "inverse",
    "energy",
    "contact",
    "simulate",
    "modes",
    "frequency_response",
    "tolerance",
)
# ... and (summary, aliases) of each that has no command of its own: a command made from its options
ANALYSIS_COMMANDS = {
    "equilibrium": (
        "Newton on the residual form under the document's loads; optionally for a target, with the tangent "
        "stiffness and sensitivities",
        (),
    ),
    "linearization": (
        "The tangent stiffness K_T at the equilibrium (or undeformed: at=undeformed), in document units",
        (),
    ),
    "energy": (
        "The minimum of the total potential (strain energy less the work of dead loads) under the joints' "
        "constraints, by IPOPT; the same report as equilibrium",
        (),
    ),
    "modes": (
        "The lowest natural frequencies and mode shapes about the equilibrium (or undeformed: at=undeformed)",
        (),
    ),
    "frequency_response": (
        "Amplitude and phase of outputs under a harmonic load over a frequency range, with resonance peaks",
        ("frf",),
    ),
    "tolerance": (
        "How the document's tolerances scatter its responses: first order from exact sensitivities (each field's "
        "share ranked), Monte Carlo of seeded samples, and the yield against the specs",
        (),
    ),
}


def loaded_registry() -> Analyses | None:
    """The analyses registry if it is imported already or plugins are named (they register on
    it: it is imported with them); else None, and this catalog stands for it."""
    if "flexmech.service.analyses" not in sys.modules and not plugin_names():
        return None
    from flexmech.service.analyses import ANALYSES

    return ANALYSES


def analysis_names() -> list[str]:
    """Every analysis' name, as `flexmech solve --analysis` takes them."""
    registry = loaded_registry()
    return list(ANALYSIS_NAMES) if registry is None else registry.names()


def command_names(
    analyses: Iterable[tuple[str, str, tuple[str, ...]]], taken: Collection[str]
) -> list[tuple[str, str, str]]:
    """(command, analysis, short help) for each (name, summary, aliases) of an analysis whose
    command name (its name with dashes) no command has, and for each of its aliases no command
    has ("Alias of <command>.")."""
    named: list[tuple[str, str, str]] = []
    for name, summary, aliases in analyses:
        command = name.replace("_", "-")
        if command in taken or any(command == c for c, _, _ in named):
            continue
        named.append((command, name, summary))
        for alias in aliases:
            if alias not in taken and all(alias != c for c, _, _ in named):
                named.append((alias, name, alias_help(command)))
    return named


def alias_help(command: str) -> str:
    """An alias' line in the list of commands, and the start of its --help."""
    return f"Alias of {command}."


def catalog_entries() -> list[tuple[str, str, tuple[str, ...]]]:
    """(name, summary, aliases) of the built-in analyses that the catalog lists as commands."""
    return [(name, *ANALYSIS_COMMANDS[name]) for name in ANALYSIS_NAMES if name in ANALYSIS_COMMANDS]
