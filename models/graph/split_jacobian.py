"""The Jacobian of a residual whose pattern is sparse but for a few dense rows and columns.

A link by elements has them: its end conditions are rows on every one of its coordinates, and
their multipliers enter every one of its rows. CasADi colors a Jacobian's columns (forward
sweeps) or its rows (reverse sweeps), one direction for the whole matrix, so a single dense
row or column forces about as many sweeps as unknowns: the Jacobian of a 64-element rod took
5 s, most of its statics build. Split instead: the dense rows by reverse sweeps (one each),
the dense columns of the other rows by forward sweeps (one each), and the sparse rest colored
as usual (a few sweeps). The entries are the same derivatives, in the same places.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

DENSE_FRACTION = 0.25  # a row (column) on more than this share of the columns (rows) is dense
DENSE_AT_LEAST = 32  # ... and on more than this many: small structures keep CasADi's own Jacobian


def jacobian(R: ca.SX, z: ca.SX) -> ca.SX:
    """dR/dz (z purely symbolic), as ca.jacobian(R, z)."""
    pattern = ca.jacobian_sparsity(R, z)
    m, n = pattern.shape
    rows = np.bincount(np.asarray(pattern.row(), dtype=int), minlength=m)
    columns = np.diff(np.asarray(pattern.colind(), dtype=int))
    dense_rows = np.flatnonzero(rows > max(DENSE_AT_LEAST, DENSE_FRACTION * n))
    dense_columns = np.flatnonzero(columns > max(DENSE_AT_LEAST, DENSE_FRACTION * m))
    if not len(dense_rows) and not len(dense_columns):
        return ca.jacobian(R, z)
    sparse_rows = np.setdiff1d(np.arange(m), dense_rows)
    sparse_columns = np.setdiff1d(np.arange(n), dense_columns)
    K = ca.SX(m, n)
    if len(sparse_rows) and len(sparse_columns):
        K[sparse_rows.tolist(), sparse_columns.tolist()] = ca.jacobian(
            R[sparse_rows.tolist()], z[sparse_columns.tolist()]
        )
    if len(sparse_rows) and len(dense_columns):
        K[sparse_rows.tolist(), dense_columns.tolist()] = ca.jacobian(
            R[sparse_rows.tolist()], z[dense_columns.tolist()]
        )
    if len(dense_rows):
        K[dense_rows.tolist(), :] = ca.jacobian(R[dense_rows.tolist()], z)
    return K
