"""Linearization: the tangent stiffness and its terms (Eqs. 26-28) in document units."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from models import Mechanism
from service.units import coordinate_kinds, matrix_to_doc


@dataclass
class TangentStiffness:
    coordinates: list[str]
    K: np.ndarray  # dR/dz, rows: generalized forces, columns: coordinates (document units)
    terms: dict[str, np.ndarray]  # I, II, III, load; they sum to K
    row_units: list[str]
    column_units: list[str]
    symmetric: bool  # in consistent units (radians), where a conservative K_T is symmetric


def tangent_stiffness(mech: Mechanism, z: np.ndarray | None = None) -> TangentStiffness:
    """K_T at nondimensional free displacements z (default: undeformed)."""
    z = np.zeros(mech.n_free) if z is None else np.asarray(z, dtype=float)
    p = mech.p()
    _, K = mech.graphs.residual_and_tangent(z, p)
    parts = mech.graphs.tangent_terms(z, p)
    terms = {name: matrix_to_doc(mech, np.asarray(t)) for name, t in zip(("I", "II", "III", "load"), parts)}
    rows, cols = coordinate_kinds(mech)
    K = np.asarray(K)  # nondimensional: lengths and forces scaled alike, angles in radians
    symmetric = bool(np.allclose(K, K.T, rtol=1e-9, atol=1e-12 * np.abs(K).max()))
    return TangentStiffness(mech.free_coordinates, matrix_to_doc(mech, K), terms,
                            [mech.doc_unit(k) for k in rows], [mech.doc_unit(k) for k in cols], symmetric)
