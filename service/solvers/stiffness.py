"""Linearization: the tangent stiffness and its terms (Eqs. 26-28) in document units."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.elements import FAMILIES
from flexmech.service.units import coordinate_kinds, matrix_to_doc


@dataclass
class TangentStiffness:
    coordinates: list[str]
    K: np.ndarray  # dR/dz, rows: generalized forces, columns: coordinates (document units)
    terms: dict[str, np.ndarray]  # I, II, III, load; they sum to K (empty with links: see below)
    row_units: list[str]
    column_units: list[str]
    symmetric: bool  # in consistent units (radians), where a conservative K_T is symmetric


def condensed(K: np.ndarray, n_bodies: int) -> np.ndarray:
    """The stiffness of the body coordinates (the first n_bodies of z) with the links' own
    unknowns solved out. Generalized forces act on the body rows only and the links' rows
    (shooting and end conditions) stay zero, so the body compliance is the leading block of
    K^-1. (K_ii alone can be singular: an inextensible link's axial force is set by the
    bodies' balance, not by its own kinematics.)"""
    if K.shape[0] == n_bodies:
        return K
    if n_bodies == 0:  # every body fixed or prescribed: nothing left to be stiff
        return np.zeros((0, 0))
    compliance = np.linalg.inv(K)[:n_bodies, :n_bodies]
    singular = np.linalg.svd(compliance, compute_uv=False)
    if singular[-1] <= 1e-12 * singular[0]:
        raise MechanismError(
            "/elements",
            "the tangent stiffness is infinite in some direction: inextensible "
            "links or rigid joints (pins, sliders) make a motion of the bodies rigid; set "
            '"axial": true on the links for a finite stiffness',
        )
    return np.linalg.inv(compliance)


def tangent_stiffness(mech: Mechanism, z: np.ndarray | None = None) -> TangentStiffness:
    """K_T over the free body coordinates at the state z (nondimensional; default: undeformed).

    With links, K_T is the Jacobian with the links' shooting unknowns condensed out; the
    seed-000 split into terms I-III belongs to curved-beam mechanisms and is left empty.
    """
    z = np.zeros(mech.n_free) if z is None else np.asarray(z, dtype=float)
    p = mech.p()
    _, K = mech.graphs.residual_and_tangent(z, p)
    n_bodies = mech.n_body_coordinates
    terms = {}
    splits = any(hasattr(FAMILIES.of(t), "split_contribution") for t in mech.structure.elements)
    if splits and not any(t.unknowns for t in mech.structure.elements):
        parts = mech.graphs.tangent_terms(z, p)
        terms = {name: matrix_to_doc(mech, np.asarray(t)) for name, t in zip(("I", "II", "III", "load"), parts)}
    rows, cols = coordinate_kinds(mech)
    K = condensed(np.asarray(K), n_bodies)  # nondimensional: lengths and forces alike, angles in rad
    symmetric = bool(K.size == 0 or np.allclose(K, K.T, rtol=1e-9, atol=1e-12 * np.abs(K).max()))
    return TangentStiffness(
        mech.free_coordinates,
        matrix_to_doc(mech, K),
        terms,
        [mech.doc_unit(k) for k in rows],
        [mech.doc_unit(k) for k in cols],
        symmetric,
    )
