"""Derivatives of outputs with respect to numeric fields, as reported (document units): the
shape every sensitivity analysis answers in (equilibrium, optimum, contact)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Sensitivities:
    parameters: list[str]
    outputs: list[str]
    matrix: np.ndarray  # (outputs, parameters), document units
    units: list[list[str]]  # "output unit / parameter unit"
    not_differentiable: list[str] = field(default_factory=list)  # why no derivative is given (none: all are)

    def to_dict(self) -> dict:
        out = {
            "parameters": self.parameters,
            "outputs": self.outputs,
            "derivatives": {
                o: dict(zip(self.parameters, [None if np.isnan(x) else x for x in row.tolist()]))
                for o, row in zip(self.outputs, self.matrix)
            },
            "units": {o: dict(zip(self.parameters, row)) for o, row in zip(self.outputs, self.units)},
        }
        if self.not_differentiable:
            out["not_differentiable"] = self.not_differentiable
        return out
