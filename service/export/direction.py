"""The Newton direction every exported task's step returns."""

from __future__ import annotations

import casadi as ca


def direction(R: ca.MX, K: ca.MX, tolerance: float) -> tuple[ca.MX, ca.MX]:
    """The Newton direction K^-1 R and |R|_inf; at a converged point (|R|_inf <= tolerance, where
    the driver stops) the factorization is skipped (a short-circuiting if_else)."""
    norm = ca.mmax(ca.fabs(R))
    return ca.if_else(norm <= tolerance, ca.MX.zeros(R.shape), ca.solve(K, R, "qr"), True), norm
