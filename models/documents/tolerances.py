"""The `tolerances` section of a document: how the made part scatters about the drawn one, and
what it must meet.

    "tolerances": {
      "fields": {"/sections/flexure/h": {"sigma": "0.1 um"},
                 "/sections/hinge/h": {"sigma": "0.1 um", "correlated_with": "/sections/flexure/h"}},
      "specs": {"end_effector.x": {"max": "0.02 mm"}, "/loads/actuation/force/1": {"min": 70, "max": 85}},
      "target": {"path": "/loads/actuation/force/1", "output": "end_effector.x", "equals": 0}
    }

`fields` maps a numeric field's JSON pointer to its distribution about the document's value: a
normal one (`sigma`, its standard deviation) or a uniform one (`plus_minus`, its half width), in
the field's unit (a bare number: the document's unit of that field). A field `correlated_with`
another moves with it: the same standardized draw (correlation 1), scaled by its own width, as
one etch moves every flexure's width. `specs` bound the responses: an output's name as a solve
reports it, the target's field (its pointer: the value the target solve finds, e.g. a closing
force), or a frequency (`frequency.1` is the lowest, Hz). `target` makes the tolerance analysis
solve for a field's value at which an output reaches a value, sample by sample.

The pointers, units and signs are checked against the compiled mechanism
(service.tolerances.fields): this module checks the shape."""

from __future__ import annotations

from pydantic import Field, model_validator

from flexmech.models.documents.fields import MAX_POINTER_CHARS, Number, OutputName, Pointer, StrictModel

MAX_TOLERANCED = 64  # fields with a distribution
MAX_SPECS = 64


class Distribution(StrictModel):
    """A normal (sigma) or uniform (plus_minus) scatter about the field's value."""

    sigma: Number | None = Field(
        default=None, description="standard deviation of a normal scatter, in the field's unit (e.g. '0.1 um')"
    )
    plus_minus: Number | None = Field(
        default=None, description="half width of a uniform scatter, in the field's unit (e.g. '0.3 um')"
    )
    correlated_with: str | None = Field(
        default=None,
        pattern=r"^/",
        max_length=MAX_POINTER_CHARS,
        description="another toleranced field this one moves with (the same standardized draw: correlation 1)",
    )

    @model_validator(mode="after")
    def _one_width(self):
        if (self.sigma is None) == (self.plus_minus is None):
            raise ValueError("give sigma (normal) or plus_minus (uniform), one of them")
        width = self.sigma if self.sigma is not None else self.plus_minus
        if isinstance(width, float) and width <= 0:
            name = "sigma" if self.sigma is not None else "plus_minus"
            raise ValueError(f"{name} must be positive, got {width:g}")
        return self

    @property
    def kind(self) -> str:
        return "normal" if self.sigma is not None else "uniform"

    @property
    def width(self) -> float | str:
        """sigma or plus_minus, as written."""
        return self.sigma if self.sigma is not None else self.plus_minus  # type: ignore[return-value]


class Spec(StrictModel):
    """min <= response <= max, in the response's unit (one bound may be left out)."""

    min: Number | None = Field(default=None, description="lowest acceptable value")
    max: Number | None = Field(default=None, description="highest acceptable value")

    @model_validator(mode="after")
    def _a_bound(self):
        if self.min is None and self.max is None:
            raise ValueError("give min, max or both")
        if isinstance(self.min, float) and isinstance(self.max, float) and self.min > self.max:
            raise ValueError(f"min ({self.min:g}) is above max ({self.max:g})")
        return self


class ToleranceTarget(StrictModel):
    """Solve, sample by sample, for the value of numeric field `path` at which `output` equals `equals`."""

    path: str = Field(
        pattern=r"^/", max_length=MAX_POINTER_CHARS, description="JSON pointer of the numeric field solved for"
    )
    output: OutputName = Field(description="the output that reaches the value")
    equals: Number = Field(description="the output's value, in its document unit")


class TolerancesSpec(StrictModel):
    fields: dict[Pointer, Distribution] = Field(
        min_length=1, max_length=MAX_TOLERANCED, description="numeric field (JSON pointer) -> its scatter"
    )
    specs: dict[OutputName, Spec] = Field(
        default={}, max_length=MAX_SPECS, description="response name -> its acceptable range (the yield counts these)"
    )
    target: ToleranceTarget | None = Field(
        default=None, description="a target solved for in every sample (its field's value is a response)"
    )
