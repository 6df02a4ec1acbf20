"""Where a kernel run's state sits in the residual form's unknowns z: the maps of the energy
form (models.graph.forms.EnergyForm), from the element counts alone. A run's report and figures
need only these; building the energy form for them took 0.1-0.16 s of every simulation."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from flexmech.models.graph.structure import Structure
from flexmech.models.kernels.layout import own_counts


@dataclass(frozen=True)
class StateMap:
    x_in_state: tuple[int, ...]  # where each coordinate of x sits in z
    multipliers_in_state: tuple[int, ...]  # where each multiplier sits in z

    def to_state(self, x: np.ndarray, multipliers: np.ndarray) -> np.ndarray:
        z = np.zeros(len(self.x_in_state) + len(self.multipliers_in_state))
        z[list(self.x_in_state)] = x
        z[list(self.multipliers_in_state)] = multipliers
        return z


@lru_cache(maxsize=16)
def state_map(structure: Structure) -> StateMap:
    """The free body coordinates first, then each element's own variables (a link's rotations
    and strains) and its equalities' multipliers, at the element's offset in z."""
    x, multipliers = list(range(len(structure.free))), []
    for t, offset in zip(structure.elements, structure.element_offsets):
        own = own_counts(t)[0]
        x += range(offset, offset + own)
        multipliers += range(offset + own, offset + t.unknowns)
    return StateMap(tuple(x), tuple(multipliers))
