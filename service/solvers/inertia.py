"""The mass matrix of a mechanism's free body coordinates, in SI units (angles in radians)."""

from __future__ import annotations

import numpy as np

from flexmech.models import Mechanism


def mass_matrix(mech: Mechanism, z: np.ndarray | None = None) -> tuple[list[str], np.ndarray]:
    """(coordinates, M): M[i, j] = d2T / dq_i' dq_j' over the free body coordinates at the
    state z (default undeformed), in kg, kg m and kg m^2. Body mass and inertia (about the
    reference point) and the mass centre's offset fill it."""
    z = np.zeros(mech.n_free) if z is None else np.asarray(z, dtype=float)
    M = np.asarray(mech.graphs.mass_matrix(z, mech.p()))[: mech.n_body_coordinates, : mech.n_body_coordinates]
    size = np.array([mech.scales.length if c < 2 else 1.0 for _, c in mech.structure.free])
    energy = mech.scales.of("energy")
    return mech.free_coordinates, M * energy / np.outer(size, size)
