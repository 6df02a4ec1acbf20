"""What a tolerance analysis measures: its responses at the nominal design, their first-order
derivatives by the toleranced fields, and a function that evaluates samples."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

# (samples x fields deviations, document units; stop) -> (samples x responses, NaN where a
# sample did not solve; each evaluated sample's status, in order: fewer when stopped)
Evaluate = Callable[[np.ndarray, Callable[[], bool]], tuple[np.ndarray, list[str]]]


@dataclass
class Responses:
    names: list[str]
    kinds: list[str]
    units: list[str]
    nominal: np.ndarray  # document units
    jacobian: np.ndarray  # responses x toleranced fields: response unit per field unit
    evaluate: Evaluate

    def linearized(self, deviations: np.ndarray) -> np.ndarray:
        """The first-order model's values of samples (samples x responses)."""
        return self.nominal[None, :] + deviations @ self.jacobian.T
