"""Conversions between the solver's nondimensional numbers and the document's units."""

from __future__ import annotations

import numpy as np

from flexmech.models import Mechanism

_ROW_KINDS = ("force", "force", "moment")
_COL_KINDS = ("length", "length", "angle")


def outputs_in_doc_units(mech: Mechanism, y_nd: np.ndarray) -> dict[str, float]:
    names, kinds = mech.graphs.output_names, mech.graphs.output_kinds
    return {n: float(v) / mech.nd_per_doc(k) for n, k, v in zip(names, kinds, np.asarray(y_nd, dtype=float).ravel())}


def residual_report(mech: Mechanism, z: np.ndarray, p: np.ndarray | None = None) -> dict:
    """The residual of a state in words an engineer reads, one definition for every report:
    residual_norm, the largest unbalanced force on a free body coordinate (residual_unit, the
    document's force unit); residual_moment, the largest unbalanced moment (its unit); and
    solver_residual, the nondimensional infinity norm of every row (elements' own rows
    included), which is what Newton's tolerance applies to."""
    R = np.asarray(mech.graphs.residual(z, mech.p() if p is None else p), dtype=float).ravel()
    free = mech.structure.free

    def largest(coordinates: tuple[int, ...]) -> float:
        rows = [abs(R[k]) for k, (_, c) in enumerate(free) if c in coordinates]
        return float(max(rows)) if rows else 0.0

    return {
        "residual_norm": largest((0, 1)) / mech.nd_per_doc("force"),
        "residual_unit": mech.doc_unit("force"),
        "residual_moment": largest((2,)) / mech.nd_per_doc("moment"),
        "residual_moment_unit": mech.doc_unit("moment"),
        "solver_residual": float(np.abs(R).max()) if R.size else 0.0,
        "solver_residual_unit": "nondimensional",
    }


def coordinate_kinds(mech: Mechanism) -> tuple[list[str], list[str]]:
    """(row kinds, column kinds) of K_T over the free coordinates."""
    rows = [_ROW_KINDS[c] for _, c in mech.structure.free]
    cols = [_COL_KINDS[c] for _, c in mech.structure.free]
    return rows, cols


def displacement_to_doc(mech: Mechanism, z_nd: np.ndarray) -> np.ndarray:
    _, cols = coordinate_kinds(mech)
    return np.array([v / mech.nd_per_doc(k) for v, k in zip(np.asarray(z_nd, dtype=float).ravel(), cols)])


def displacement_from_doc(mech: Mechanism, values) -> np.ndarray:
    _, cols = coordinate_kinds(mech)
    return np.array([v * mech.nd_per_doc(k) for v, k in zip(np.asarray(values, dtype=float).ravel(), cols)])


def matrix_to_doc(mech: Mechanism, K_nd: np.ndarray) -> np.ndarray:
    """K[i, j] in (row unit) / (column unit) of the document, e.g. uN/mm, uN, uN*mm/deg."""
    rows, cols = coordinate_kinds(mech)
    r = np.array([1.0 / mech.nd_per_doc(k) for k in rows])
    c = np.array([mech.nd_per_doc(k) for k in cols])
    return np.asarray(K_nd) * r[:, None] * c[None, :]


def wrench_to_doc(mech: Mechanism, w_nd: np.ndarray) -> np.ndarray:
    """Per body [Fx, Fy, M] (3 * n_bodies, nondim) in document units."""
    w = np.asarray(w_nd, dtype=float).reshape(-1, 3).copy()
    w[:, :2] /= mech.nd_per_doc("force")
    w[:, 2] /= mech.nd_per_doc("moment")
    return w
