"""The design problem of a document's `optimize` section (the optimize analysis): its design
variables, objective, constraints and load cases."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from flexmech.models.documents.fields import MAX_POINTER_CHARS, Name, Number, OutputName, Pointer, StrictModel


class DesignVariable(StrictModel):
    """A numeric field of the document that the optimizer may change, in document units."""

    path: str = Field(pattern=r"^/", max_length=MAX_POINTER_CHARS, description="JSON pointer of a numeric field")
    lower: float | None = Field(default=None, description="lower bound, document units")
    upper: float | None = Field(default=None, description="upper bound, document units")
    scale: float | None = Field(default=None, gt=0, description="typical size (default: the start value)")


class OptimizationObjective(StrictModel):
    output: OutputName = Field(
        description="an output name, as /v1/solve reports them (e.g. reactions.tip.Fy), or yield (the first-order "
        "share of parts meeting the tolerances' specs)"
    )
    case: Name | None = Field(default=None, description="load case (required with more than one)")
    sense: Literal["minimize", "maximize"] = "minimize"
    sigmas: float | None = Field(
        default=None,
        ge=0,
        le=10,
        description="robust: mean + k sigma (minimize) or mean - k sigma (maximize), first order over the "
        "document's tolerances",
    )


class OptimizationConstraint(StrictModel):
    """lower <= output <= upper, or output = equals (document units)."""

    output: OutputName
    case: Name | None = None
    lower: float | None = None
    upper: float | None = None
    equals: float | None = None
    sigmas: float | None = Field(
        default=None,
        ge=0,
        le=10,
        description="robust: mean + k sigma <= upper and mean - k sigma >= lower, first order over the document's "
        "tolerances",
    )

    @model_validator(mode="after")
    def _some_bound(self):
        if self.equals is not None and (self.lower is not None or self.upper is not None):
            raise ValueError("give equals, or lower and/or upper, not both")
        if self.equals is None and self.lower is None and self.upper is None:
            raise ValueError("give equals, lower or upper")
        return self


class LoadCase(StrictModel):
    """The document with some numeric fields changed (document units)."""

    overrides: dict[Pointer, Number] = {}


class ResponseDamping(StrictModel):
    """Rayleigh damping D = alpha M + beta K of the frequency responses a problem names."""

    mass: float = Field(default=0.0, ge=0, description="alpha (1/s)")
    stiffness: float = Field(default=0.0, ge=0, description="beta (s)")


class OptimizeSpec(StrictModel):
    """A design problem (Cammarata et al. 2022 Sec. 5.2, Lan 2005 Sec. 5.6): one NLP whose unknowns are the
    design variables and the equilibrium state of every load case."""

    design: list[DesignVariable] = Field(min_length=1, max_length=64)
    objective: OptimizationObjective
    constraints: list[OptimizationConstraint] = Field(default=[], max_length=256)
    cases: dict[Name, LoadCase] = Field(default={}, description="load cases (default: the document as it is)")
    starts: int = Field(
        default=1, ge=1, le=64, description="multi-start: the document's values, then random points in the bounds"
    )
    seed: int = Field(default=0, ge=0, description="random seed of the extra starts")
    max_iterations: int = Field(default=500, ge=1, le=100_000)
    tolerance: float = Field(default=1e-9, gt=0, le=1e-2, description="IPOPT tol (scaled problem)")
    damping: ResponseDamping = Field(
        default=ResponseDamping(), description="damping of the response(...) outputs (default: none)"
    )
