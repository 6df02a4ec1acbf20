"""Derivatives of outputs with respect to numeric fields, as reported (document units): the
shape every sensitivity analysis answers in (equilibrium, optimum, contact)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Sensitivities:
    parameters: list[str]
    outputs: list[str]
    matrix: np.ndarray  # (outputs, parameters), document units
    units: list[list[str]]  # "output unit / parameter unit"

    def to_dict(self) -> dict:
        return {"parameters": self.parameters, "outputs": self.outputs,
                "derivatives": {o: dict(zip(self.parameters, row.tolist())) for o, row in zip(self.outputs, self.matrix)},
                "units": {o: dict(zip(self.parameters, row)) for o, row in zip(self.outputs, self.units)}}
