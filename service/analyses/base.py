"""The contract of an analysis, and the registry that /v1/solve, the CLI, the client, batch and
the workbench take their analyses from.

An analysis has a name, a one-line summary, and two pydantic models: its `Options` (the
request fields it reads, typed and described: the HTTP schema, the CLI's flags, the client's
docstrings and the workbench's form are made from them) and its `Result` (what its report
holds). It says:
  report(mech, newton, options) -> dict   the JSON-able report of one mechanism (document
                                          units), raising MechanismError naming the field for
                                          bad input; non-convergence is a status in the report
  point(mech, p, guess, newton)           one point of a sweep: an EquilibriumResult at the
                                          nondimensional parameters p from the state `guess`
                                          (sweepable analyses only)
  report_size(mech, options)              how many numbers its report will hold, counted from the
                                          request before any work (service.costs bounds a
                                          response and a stored job by it)
A new analysis is one module with a subclass and one line `ANALYSES.register(...)`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from flexmech.models import Mechanism, MechanismError
from flexmech.models.errors import pointer_of
from flexmech.service.solvers.equilibrium import EquilibriumResult
from flexmech.service.solvers.newton import NewtonOptions


class AnalysisOptions(BaseModel):
    """The request fields of an analysis (none by default). Each field's description is the
    help the CLI, the client and the workbench show; `json_schema_extra={"unit": ...}` names
    its unit, `{"document_default": "/pointer"}` the document field the workbench starts from."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class AnalysisResult(BaseModel):
    """What every report holds; an analysis' Result adds its own fields."""

    model_config = ConfigDict(extra="allow")

    analysis: str
    name: str = Field(description="the document's name")
    status: str = Field(
        description="converged, not_converged, singular, time_limit, infeasible (finished: "
        "a simulation reached its end)"
    )
    message: str = ""
    warnings: list[str] = Field(default_factory=list)


@dataclass(frozen=True)
class ReportSize:
    """The numbers a report will hold, counted before any work: `numbers` in all, `terms` saying
    what they are made of (60 outputs x 100400 frequencies x 2), and the request field that
    drives them (`pointer`) with what to change there (`change`)."""

    numbers: int
    terms: str
    pointer: str
    change: str


def state_numbers(mech: Mechanism) -> int:
    """A solved state's share of a report: every output, every body displacement (with units)."""
    return 2 * len(mech.graphs.output_names) + 2 * mech.n_body_coordinates


def drawn_numbers(mech: Mechanism) -> int:
    """One drawn state: x and y of every centre-line point and its stress, and every body's pose."""
    points: int = sum(count for _, _, count, _, _ in mech.graphs.shape_segments)
    return 3 * points + 3 * len(mech.structure.bodies)


@dataclass(frozen=True)
class AnalysisRequest:
    """What an analysis is asked: the Newton options, and its typed options (a mapping is
    checked into the analysis' Options first, its problems named by JSON pointer)."""

    options: NewtonOptions = NewtonOptions()
    given: AnalysisOptions | Mapping[str, Any] | None = None


class Analysis(ABC):
    name: ClassVar[str]
    summary: ClassVar[str]
    sweepable: ClassVar[bool] = False
    long: ClassVar[bool] = False  # may run for seconds: never on the worker kept for small requests
    Options: ClassVar[type[AnalysisOptions]] = AnalysisOptions
    Result: ClassVar[type[AnalysisResult]] = AnalysisResult
    # (flag, suffixes, help) of each figure its command can draw (flexmech <name> --<flag> OUT): draw() makes them
    figures: ClassVar[tuple[tuple[str, tuple[str, ...], str], ...]] = ()
    aliases: ClassVar[tuple[str, ...]] = ()  # other names of its command (flexmech frf)

    def run(self, mech: Mechanism, request: AnalysisRequest = AnalysisRequest()) -> dict[str, Any]:
        """The report of one mechanism."""
        return self.report(mech, request.options, self.options_of(request.given))

    @abstractmethod
    def report(self, mech: Mechanism, newton: NewtonOptions, options: Any) -> dict[str, Any]:
        """The report of one mechanism under this analysis' typed options."""

    def draw(
        self, mech: Mechanism, newton: NewtonOptions, options: Any, report: dict[str, Any], figure: str, path: Path
    ) -> None:
        """Draw the figure named by `figure` (one of `figures`) of a report into `path`."""
        raise MechanismError(f"/{figure}", f"the {self.name} analysis draws no {figure}")

    def options_of(self, given: AnalysisOptions | Mapping[str, Any] | None) -> AnalysisOptions:
        """Typed options: as given, or checked from a mapping (MechanismError at the field)."""
        if isinstance(given, self.Options):
            return given
        try:
            return self.Options.model_validate(dict(given or {}))
        except ValidationError as exc:
            first = exc.errors()[0]
            raise MechanismError(pointer_of(tuple(first["loc"])), first["msg"]) from None

    def report_size(self, mech: Mechanism, options: Any) -> ReportSize:
        """The numbers the report of `mech` under these typed options will hold (before any
        work). The default is a solved state's; an analysis whose report grows with its options
        (points, modes, outputs, steps) counts them."""
        return ReportSize(state_numbers(mech), "the outputs and displacements of one state", "/document", "")

    def point(self, mech: Mechanism, p: np.ndarray, guess: np.ndarray, options: NewtonOptions) -> EquilibriumResult:
        raise MechanismError(
            "/analysis", f"the {self.name} analysis has no points to sweep (sweepable: equilibrium and energy)"
        )


class Analyses:
    """The registry. Listeners (the CLI's command maker) hear of every analysis, registered
    before or after they listen."""

    def __init__(self, analyses: list[Analysis]):
        self._by_name: dict[str, Analysis] = {}
        self._listeners: list[Callable[[Analysis], None]] = []
        for analysis in analyses:
            self.register(analysis)

    def register(self, analysis: Analysis) -> Analysis:
        if analysis.name in self._by_name and self._by_name[analysis.name] is not analysis:
            raise ValueError(f"an analysis named '{analysis.name}' is registered already")
        if analysis.name not in self._by_name:
            self._by_name[analysis.name] = analysis
            for listener in self._listeners:
                listener(analysis)
        return analysis

    def listen(self, listener: Callable[[Analysis], None]) -> None:
        self._listeners.append(listener)
        for analysis in list(self._by_name.values()):
            listener(analysis)

    def names(self) -> list[str]:
        return list(self._by_name)

    def __iter__(self) -> Iterator[Analysis]:
        return iter(list(self._by_name.values()))

    def named(self, name: str, pointer: str = "/analysis") -> Analysis:
        if name not in self._by_name:
            raise MechanismError(pointer, f"unknown analysis '{name}' (analyses: {', '.join(self._by_name)})")
        return self._by_name[name]

    def describe(self) -> list[dict[str, Any]]:
        """Each analysis with its options' and result's JSON schemas (GET /v1/analyses)."""
        return [
            {
                "name": a.name,
                "summary": a.summary,
                "sweepable": a.sweepable,
                "options": a.Options.model_json_schema(),
                "result": a.Result.model_json_schema(),
            }
            for a in self._by_name.values()
        ]
