"""The natural modes of a mechanism about a state z of its residual form (an equilibrium, or the
undeformed state), in one of two coordinate sets:

- the energy form's unknowns (models.graph.modal) when every element has an energy: the
  bodies' coordinates and the elements' own (a link by elements: its rotations and strains,
  with its consistent mass); the stiffness is the Hessian of the Lagrangian at the state's
  multipliers, so prestress and load stiffness are in it;
- the bodies' coordinates otherwise (a constant-stiffness curved beam, a link by shooting):
  the tangent stiffness K_T with the elements' unknowns condensed out (service.solvers.stiffness),
  the elements massless (the seeds' models carry no mass), the bodies' masses.

Both are nondimensional with time in seconds, so omega comes out in rad/s.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.service.buffered import BufferedCall
from flexmech.service.solvers.stiffness import condensed
from flexmech.service.vibration.eigen import Eigen, vibration_eigen


@dataclass
class ModalSystem:
    """K, M and G in one coordinate set, and what the report reads in it."""

    coordinates: list[str]
    K: np.ndarray
    G: np.ndarray | None
    owners: list[str]  # "bodies/<name>", "elements/<name>"
    masses: list[np.ndarray]  # per owner
    uniform: np.ndarray  # (n, 2): generalized forces of a unit uniform acceleration along x, y
    total_mass: float  # nondimensional
    n_body: int  # the first n_body coordinates are the free body coordinates
    point_owners: list[str]  # the element of each mass point
    points: np.ndarray  # (2, k) positions of the elements' mass points (nondimensional)
    point_jacobian: np.ndarray  # (2k, n)
    coordinates_set: str  # "elements" or "bodies"
    x_in_state: list[int]  # where each coordinate sits in the residual form's z
    multipliers_in_state: list[int]  # where the constraints' multipliers sit (energy form)

    @property
    def M(self) -> np.ndarray:
        return sum(self.masses, np.zeros_like(self.K))


@dataclass
class MechanismModes:
    system: ModalSystem
    eigen: Eigen


def modal_system(mech: Mechanism, z: np.ndarray | None, p: np.ndarray | None = None) -> ModalSystem:
    """The system about z (None: undeformed) at the parameters p (None: the mechanism's), in the
    energy form's unknowns where it exists."""
    z = np.zeros(mech.n_free) if z is None else np.asarray(z, dtype=float)
    p = mech.p() if p is None else p
    try:
        form = mech.graphs.modal_form
    except MechanismError:
        return _body_system(mech, z, p)
    x, lam = z[list(form.x_in_state)], z[list(form.multipliers_in_state)]
    n = len(x)
    K, G, stacked, F, positions, J = _state_call(form.state)(x, lam, p)
    return ModalSystem(
        list(form.unknowns),
        K,
        G.reshape(form.n_equalities, n),
        list(form.owners),
        list(stacked.reshape(len(form.owners), n, n)),
        F.reshape(n, 2),
        float(form.total_mass(p)),
        len(mech.structure.free),
        list(form.point_owners),
        positions.reshape(2, -1),
        J.reshape(-1, n),
        "elements",
        list(form.x_in_state),
        list(form.multipliers_in_state),
    )


@lru_cache(maxsize=16)
def _state_call(state: ca.Function) -> BufferedCall:
    """The modal state through buffers of its own (no conversion of its matrices), once per graph."""
    return BufferedCall(state)


def _body_system(mech: Mechanism, z: np.ndarray, p: np.ndarray) -> ModalSystem:
    n = mech.n_body_coordinates
    _, K = mech.graphs.residual_and_tangent(z, p)
    M = np.asarray(mech.graphs.mass_matrix(z, p), dtype=float)[:n, :n]
    free = mech.structure.free
    owners, masses = [], []
    for body in sorted({b for b, _ in free}):
        rows = [k for k, (b, _) in enumerate(free) if b == body]
        block = np.zeros_like(M)
        block[np.ix_(rows, rows)] = M[np.ix_(rows, rows)]
        if np.abs(block).max(initial=0.0) > 0.0:
            owners.append(f"bodies/{mech.structure.bodies[body]}")
            masses.append(block)
    along = np.array([[1.0 if c == axis else 0.0 for axis in (0, 1)] for _, c in free]).reshape(n, 2)
    uniform = M @ along
    return ModalSystem(
        list(mech.free_coordinates),
        condensed(np.asarray(K), n),
        None,
        owners,
        masses,
        uniform,
        float(along[:, 0] @ M @ along[:, 0]),
        n,
        [],
        np.zeros((2, 0)),
        np.zeros((0, n)),
        "bodies",
        list(range(n)),
        [],
    )


def mechanism_modes(
    mech: Mechanism, z: np.ndarray | None, count: int | None, p: np.ndarray | None = None
) -> MechanismModes:
    """The `count` lowest natural modes about z (None: every one), at the parameters p."""
    system = modal_system(mech, z, p)
    return MechanismModes(system, vibration_eigen(system.K, system.M, system.G, count))
