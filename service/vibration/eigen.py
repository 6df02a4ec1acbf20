"""The generalized eigenproblem of small vibration, K phi = omega^2 M phi, on the null space of
the constraints' Jacobian G, with the motions that carry no mass condensed out statically.

A massless motion (a spring's or a closed-form flexure's, a link without density, the
rotation of a body given no inertia) has no inertia to vibrate with: it follows the massive
ones quasi-statically. Splitting the constrained space by M's null space into massive (R) and
massless (N) directions,

    K_hat = R^T K T,   M_hat = R^T M R,   T = R - N (N^T K N)^-1 N^T K R,

is exact for them (Guyan's condensation, with no error where the mass is zero). Shapes come back
in the full unknowns, mass-normalized: phi^T M phi = 1.

Small structures are solved densely (every eigenvalue). Larger ones (more than DENSE_LIMIT
unknowns, a symmetric K, a few modes asked) never form the null space: shift-invert Lanczos near
zero (scipy's eigsh) on the sparse bordered pencil

    [[K, G^T], [G, 0]] v = lambda [[M, 0], [0, 0]] v,

whose factorization solves the constraints and the massless unknowns at once (the same exact
condensation), and which resolves the low frequencies to full relative accuracy whatever the
highest one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.linalg import eig, eigh, null_space
from scipy.sparse.linalg import eigsh

from flexmech.models import MechanismError

DENSE_LIMIT = 400
RIGID = 1e-12  # |omega^2| below this fraction of the largest is a zero-frequency (rigid) mode
MASSLESS = 1e-12  # a direction whose mass is below this fraction of the largest carries none


@dataclass
class Eigen:
    omega_squared: np.ndarray  # ascending, signed (negative: an unstable equilibrium)
    shapes: np.ndarray  # (unknowns, modes), mass-normalized
    kinds: list[str]  # per mode: "elastic", "rigid" (zero frequency) or "unstable"
    largest: float  # the largest |omega^2| (rad^2/s^2): the scale rigid modes are judged by
    available: int  # how many modes the structure has (its massive directions)
    symmetric: bool  # False: a non-conservative tangent stiffness (frequencies from its real part)
    left: np.ndarray  # (unknowns, modes): a force f excites mode k by left[:, k] . f (= shapes if symmetric)
    feedthrough: np.ndarray | None  # (unknowns, unknowns): the massless directions' static compliance


def vibration_eigen(K: np.ndarray, M: np.ndarray, G: np.ndarray | None, count: int | None) -> Eigen:
    """The `count` lowest modes (None: every one; MechanismError at /count when the structure
    has fewer)."""
    n = K.shape[0]
    if count is not None and n > DENSE_LIMIT and count < n // 4 and _symmetric(K):
        return _sparse_lowest(K, M, G, count)
    Z = null_space(G) if G is not None and G.size else np.eye(n)
    Kr, Mr = Z.T @ K @ Z, Z.T @ M @ Z
    Mr = 0.5 * (Mr + Mr.T)
    weights, U = eigh(Mr)
    heaviest = weights.max(initial=0.0)
    if heaviest <= 0.0:
        raise MechanismError(
            "/bodies", "the mechanism has no mass that can move: give a body a mass or a material a density"
        )
    massive = weights > MASSLESS * heaviest
    R, N = U[:, massive], U[:, ~massive]
    symmetric = _symmetric(Kr)
    T, T_left, feedthrough = R, R, None
    if N.shape[1]:
        T = R - N @ _massless_response(Kr, N, R)
        T_left = T if symmetric else R - N @ _massless_response(Kr.T, N, R)
        feedthrough = Z @ N @ np.linalg.solve(N.T @ Kr @ N, N.T @ Z.T)
    K_hat, M_hat = R.T @ Kr @ T, R.T @ Mr @ R
    available = K_hat.shape[0]
    count = available if count is None else count
    if count > available:
        raise MechanismError(
            "/count", f"{count} modes asked, but the mechanism has {available} (its coordinates that carry mass)"
        )
    values, Y, W, largest = _lowest(K_hat, M_hat, count, symmetric)
    kinds = ["rigid" if abs(v) <= RIGID * largest else "unstable" if v < 0 else "elastic" for v in values]
    return Eigen(values, Z @ T @ Y, kinds, largest, available, symmetric, Z @ T_left @ W, feedthrough)


def _symmetric(K: np.ndarray) -> bool:
    return bool(np.allclose(K, K.T, rtol=1e-9, atol=1e-12 * max(np.abs(K).max(), 1e-300)))


def _sparse_lowest(K: np.ndarray, M: np.ndarray, G: np.ndarray | None, count: int) -> Eigen:
    """The `count` lowest modes by shift-invert on the sparse bordered pencil. The scale rigid
    modes are judged by is the largest diagonal stiffness over the smallest diagonal mass (an
    upper estimate of the largest omega^2); `available` counts the unknowns with mass less the
    constraints."""
    n = K.shape[0]
    stiffness, mass = sp.csc_matrix(0.5 * (K + K.T)), sp.csc_matrix(0.5 * (M + M.T))
    rows = 0 if G is None else G.shape[0]
    heavy = np.diag(M)[np.diag(M) > 0]
    if not heavy.size:
        raise MechanismError(
            "/bodies", "the mechanism has no mass that can move: give a body a mass or a material a density"
        )
    available = heavy.size - rows
    if count > available:
        raise MechanismError(
            "/count", f"{count} modes asked, but the mechanism has {available} (its coordinates that carry mass)"
        )
    top = float(np.abs(np.diag(K)).max() / heavy.min())
    if rows:
        constraints = sp.csc_matrix(G)
        stiffness = sp.bmat([[stiffness, constraints.T], [constraints, None]], format="csc")
        mass = sp.bmat([[mass, None], [None, sp.csc_matrix((rows, rows))]], format="csc")
    values, vectors = eigsh(stiffness, count, mass, sigma=-1e-14 * top, which="LM")
    order = np.argsort(values)
    values, shapes = values[order], vectors[:n, order]
    shapes = shapes / np.sqrt(np.einsum("im,ij,jm->m", shapes, M, shapes))
    kinds = ["rigid" if abs(v) <= RIGID * top else "unstable" if v < 0 else "elastic" for v in values]
    return Eigen(values, shapes, kinds, top, available, True, shapes, None)


def _massless_response(Kr: np.ndarray, N: np.ndarray, R: np.ndarray) -> np.ndarray:
    """(N^T K N)^-1 N^T K R: how the massless directions follow the massive ones."""
    Knn = N.T @ Kr @ N
    singular = np.linalg.svd(Knn, compute_uv=False)
    if singular[-1] <= 1e-12 * max(np.abs(Kr).max(), 1e-300):
        raise MechanismError(
            "/elements",
            "a motion of the mechanism has neither mass nor stiffness (a massless body or element "
            "free to move): give it a mass or a density, or hold it",
        )
    return np.linalg.solve(Knn, N.T @ Kr @ R)


def _lowest(
    K: np.ndarray, M: np.ndarray, count: int, symmetric: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(omega^2, M-normalized right vectors Y, left vectors W with W^T M Y = I, the largest
    |omega^2|) of the `count` lowest modes."""
    if symmetric:
        values, Y = eigh(0.5 * (K + K.T), M)
        return values[:count], Y[:, :count], Y[:, :count], float(np.abs(values).max(initial=0.0))
    values, W, Y = eig(K, M, left=True, right=True)
    order = np.argsort(values.real)
    values, Y, W = values.real[order], Y.real[:, order], W.real[:, order]
    Y = Y / np.sqrt(np.einsum("im,ij,jm->m", Y, M, Y))
    W = W / np.einsum("im,ij,jm->m", W, M, Y)
    return values[:count], Y[:, :count], W[:, :count], float(np.abs(values).max(initial=0.0))
