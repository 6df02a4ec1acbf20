"""Natural modes of small vibration about an equilibrium: the generalized eigenproblem of the
stiffness (the Hessian of the Lagrangian) and the mass matrix on the constraints' null space."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np
from scipy.linalg import eigh, null_space

from flexmech.models.graph.dynamics import DynamicsForm, dynamics_form
from flexmech.models.graph.structure import Structure


@lru_cache(maxsize=16)
def form_of(structure: Structure, moving: tuple[int, ...] = ()) -> DynamicsForm:
    """The dense dynamics form (models.graph.dynamics): small eigenproblems and reference checks; time
    stepping runs on element kernels (service.dynamics.engine)."""
    return dynamics_form(structure, moving)


@dataclass
class Modes:
    omegas: np.ndarray  # rad/s, ascending
    shapes: np.ndarray  # (unknowns, modes): in x, mass-normalized


@lru_cache(maxsize=16)
def _hessian(structure: Structure) -> ca.Function:
    from flexmech.models.graph.forms import symbolic_energy

    s = symbolic_energy(structure)
    g = ca.vertcat(*[row for _, row in s.equalities]) if s.equalities else ca.SX(0, 1)
    lam = ca.SX.sym("lam", g.numel())
    K = ca.hessian(s.potential + ca.dot(lam, g), s.x)[0]
    return ca.Function("stiffness", [s.x, lam, s.ctx.p], [K])


def natural_modes(structure: Structure, p: np.ndarray, x: np.ndarray, lam: np.ndarray) -> Modes:
    """The modes about the equilibrium (x, lam) at parameters p."""
    form = form_of(structure)
    K = np.asarray(_hessian(structure)(x, lam, p), dtype=float)
    M = np.asarray(form.mass(x, p), dtype=float)
    G = np.asarray(form.constraint_jacobian(x, p), dtype=float).reshape(form.n_equalities, len(x))
    Z = null_space(G) if G.size else np.eye(len(x))
    values, vectors = eigh(Z.T @ K @ Z, Z.T @ M @ Z)
    return Modes(np.sqrt(np.maximum(values, 0.0)), Z @ vectors)


def highest_frequency(structure: Structure, p: np.ndarray, x: np.ndarray) -> float:
    """The highest natural frequency (rad/s) of the discretized mechanism about x, its
    constraints' forces taken as zero (the start of a run)."""
    form = form_of(structure)
    return float(natural_modes(structure, p, x, np.zeros(form.n_equalities)).omegas.max(initial=0.0))
