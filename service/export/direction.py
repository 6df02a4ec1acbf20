"""The Newton direction every exported task's step returns."""

from __future__ import annotations

import casadi as ca


def direction(R: ca.MX, K: ca.MX) -> tuple[ca.MX, ca.MX]:
    """The Newton direction K^-1 R (sparse QR, generated without allocation) and |R|_inf. The
    factorization runs at the converged point too: skipping it there with a short-circuiting
    if_else made the gripper's warm call no faster (the branch becomes a called function)."""
    return ca.solve(K, R, "qr"), ca.mmax(ca.fabs(R))
