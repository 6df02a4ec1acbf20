"""The document's `sweep` section: a load path that `flexmech sweep` and the sweep job follow
(service.solvers.sweep), from start to stop or until an output reaches a value."""

from __future__ import annotations

from pydantic import Field, model_validator

from flexmech.models.documents.fields import Number, OutputName, Pointer, StrictModel


class SweepUntil(StrictModel):
    output: OutputName = Field(description="scalar output name, e.g. end_effector.x")
    equals: Number


class SweepSpec(StrictModel):
    """A load path: `path` (a numeric field) goes from start to stop in `steps` steps; with
    `until`, the path ends where the named output reaches the given value."""

    path: Pointer
    start: Number
    stop: Number | None = None
    steps: int = Field(default=100, ge=1)
    until: SweepUntil | None = None

    @model_validator(mode="after")
    def _an_end(self):
        if self.stop is None and self.until is None:
            raise ValueError("give 'stop' or 'until'")
        return self
