"""The contract of an analysis, and the registry that /v1/solve, the CLI and the sweep job
dispatch through.

An analysis has a name and a one-line summary, and says:
  run(mech, request) -> report    the JSON-able report of one mechanism (document units),
                                   raising MechanismError naming the field for bad input;
                                   non-convergence is a status in the report
  point(mech, p, guess, options)   one point of a sweep: an EquilibriumResult at the
                                   nondimensional parameters p from the state `guess`
                                   (sweepable analyses only)
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from models import Mechanism, MechanismError
from service.equilibrium import EquilibriumResult
from service.newton import NewtonOptions


@dataclass(frozen=True)
class AnalysisRequest:
    """What an analysis reads from a request: the Newton options, and the request's own fields
    (target, stiffness, sensitivities, at, displacements, ...: JSON as given)."""

    options: NewtonOptions = NewtonOptions()
    fields: Mapping[str, Any] = field(default_factory=dict)

    def get(self, name: str, default: Any = None) -> Any:
        value = self.fields.get(name)
        return default if value is None else value


class Analysis(ABC):
    name: str
    summary: str
    sweepable: bool = False

    @abstractmethod
    def run(self, mech: Mechanism, request: AnalysisRequest) -> dict:
        """The report of one mechanism."""

    def point(self, mech: Mechanism, p: np.ndarray, guess: np.ndarray, options: NewtonOptions) -> EquilibriumResult:
        raise MechanismError("/analysis", f"the {self.name} analysis has no points to sweep "
                             "(sweepable: equilibrium and energy)")


class Analyses:
    def __init__(self, analyses: list[Analysis]):
        self._by_name = {a.name: a for a in analyses}

    def names(self) -> list[str]:
        return list(self._by_name)

    def named(self, name: str, pointer: str = "/analysis") -> Analysis:
        if name not in self._by_name:
            raise MechanismError(pointer, f"unknown analysis '{name}' (analyses: {', '.join(self._by_name)})")
        return self._by_name[name]

    def describe(self) -> list[dict]:
        return [{"name": a.name, "summary": a.summary, "sweepable": a.sweepable} for a in self._by_name.values()]
