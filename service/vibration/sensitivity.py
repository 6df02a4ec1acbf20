"""Exact derivatives of natural frequencies with respect to numeric fields.

In the residual form's unknowns z the modes solve K_T(z, p) v = lambda M_z(z, p) v (K_T = dR/dz:
the Lagrangian's Hessian bordered by the constraints' Jacobian, the multipliers' rows of v being
the mode's constraint forces; massless unknowns following statically). For a simple eigenvalue,
with w the left vector (v itself when K_T is symmetric),

    d lambda / dp = w . (d(K_T v)/dp - lambda d(M_z v)/dp) / (w . M_z v),

the total derivatives taking the state along: dz/dp = -K_T^-1 dR/dp at an equilibrium (held at
the undeformed state, z does not move). The terms are CasADi's exact derivatives.

Repeated eigenvalues (a relative gap below REPEATED) are not differentiable one by one: a
parameter splits them along directions the parameter itself chooses. For them the derivative of
their mean is returned, on every mode of the cluster, and the cluster is named."""

from __future__ import annotations

import math
from functools import lru_cache

import casadi as ca
import numpy as np

from flexmech.models import Mechanism
from flexmech.models.graph.assembly import graphs_for
from flexmech.models.graph.modal import state_mass
from flexmech.models.graph.structure import Structure
from flexmech.service.vibration.modes import MechanismModes, mechanism_modes

REPEATED = 1e-6


@lru_cache(maxsize=16)
def _terms(structure: Structure) -> ca.Function:
    """(z, p, v, w) -> (K_T, dR/dp, M_z, d(w.K_T v)/dz, d(w.K_T v)/dp, d(w.M_z v)/dz, d(w.M_z v)/dp)."""
    graphs = graphs_for(structure)
    n = structure.n_unknowns
    z, p = ca.SX.sym("z", n), ca.SX.sym("p", len(structure.parameters))
    v, w = ca.SX.sym("v", n), ca.SX.sym("w", n)
    R = graphs.residual(z, p)
    M = state_mass(structure)(z, p)
    stiffness = ca.dot(w, ca.jtimes(R, z, v))
    inertia = ca.dot(w, ca.mtimes(M, v))
    return ca.Function(
        "frequency_terms",
        [z, p, v, w],
        [
            ca.jacobian(R, z),
            ca.jacobian(R, p),
            M,
            ca.gradient(stiffness, z),
            ca.gradient(stiffness, p),
            ca.gradient(inertia, z),
            ca.gradient(inertia, p),
        ],
        dict(cse=True),
    )


def frequency_sensitivities(
    mech: Mechanism, z: np.ndarray, found: MechanismModes, slots: list[int], equilibrium: bool
) -> tuple[np.ndarray, list[list[int]]]:
    """(d frequency / d parameter in Hz per document unit (modes x slots), the clusters of
    repeated modes (0-based))."""
    terms = _terms(mech.structure.unnamed)
    p = mech.p()
    eigen = found.eigen
    K = np.asarray(terms(z, p, np.zeros(len(z)), np.zeros(len(z)))[0], dtype=float)
    rows = []
    for k, value in enumerate(eigen.omega_squared):
        v, w = state_vectors(found, K, k)
        _, R_p, M, Kz, Kp, Mz, Mp = (np.asarray(a, dtype=float) for a in terms(z, p, v, w))
        partial_z = (Kz - value * Mz).ravel()
        partial_p = (Kp - value * Mp).ravel()[slots]
        if equilibrium:
            partial_p = partial_p - partial_z @ np.linalg.solve(K, R_p[:, slots])
        rows.append(partial_p / float(w @ M @ v))
    d_lambda = np.array(rows).reshape(len(eigen.omega_squared), len(slots))
    clusters = _clusters(eigen.omega_squared)
    for cluster in clusters:
        d_lambda[cluster] = d_lambda[cluster].mean(axis=0)
    omega = np.sqrt(np.abs(eigen.omega_squared))
    with np.errstate(divide="ignore", invalid="ignore"):
        d_frequency = d_lambda / (2 * omega[:, None]) / (2 * math.pi)
    factors = np.array([mech.nd_per_doc(mech.parameters[s].kind) for s in slots])
    return d_frequency * factors[None, :], clusters


def state_mode(mech: Mechanism, z: np.ndarray, p: np.ndarray, k: int) -> tuple[np.ndarray, float]:
    """Mode k (0-based) about (z, p) as a right vector over z, and its omega^2."""
    found = mechanism_modes(mech, z, k + 1, p)
    K = np.asarray(mech.graphs.residual_and_tangent(z, p)[1], dtype=float)
    v, _ = state_vectors(found, K, k)
    return v, float(found.eigen.omega_squared[k])


def state_vectors(found: MechanismModes, K: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Mode k's right and left vectors over z."""
    system, eigen = found.system, found.eigen
    n = K.shape[0]
    if system.coordinates_set == "elements (contact)":  # its multipliers are the contact problem's: drawn only
        v = np.zeros(n)
        v[system.x_in_state] = eigen.shapes[: len(system.x_in_state), k]
        return v, v
    if system.coordinates_set == "elements":
        phi = eigen.shapes[:, k]
        v = np.zeros(n)
        v[system.x_in_state] = phi
        if system.G is not None and system.G.size:
            force = eigen.omega_squared[k] * (system.M @ phi) - system.K @ phi
            v[system.multipliers_in_state] = np.linalg.lstsq(system.G.T, force, rcond=None)[0]
        return v, v  # the Hessian bordered by G is symmetric
    b, own = slice(0, system.n_body), slice(system.n_body, n)
    right, left = np.zeros(n), np.zeros(n)
    right[b], left[b] = eigen.shapes[:, k], eigen.left[:, k]
    if n > system.n_body:
        right[own] = -np.linalg.solve(K[own, own], K[own, b] @ right[b])
        left[own] = -np.linalg.solve(K[own, own].T, K[b, own].T @ left[b])
    return right, left


def _clusters(values: np.ndarray) -> list[list[int]]:
    clusters: list[list[int]] = []
    for k in range(1, len(values)):
        if abs(values[k] - values[k - 1]) <= REPEATED * max(abs(values[k]), abs(values[k - 1])):
            if clusters and clusters[-1][-1] == k - 1:
                clusters[-1].append(k)
            else:
                clusters.append([k - 1, k])
    return clusters
