"""The reference for limit loads: natural continuation (Newton from the last accepted state at
the next load) with bisection on the load where the branch ends. A state is accepted only if
Newton converges to a stable state near the last one (its body coordinates move less than `jump`, nondimensional): past a limit point the branch no longer
exists, and Newton either fails or jumps to another branch."""

from __future__ import annotations

import numpy as np

from flexmech.service.solvers.continuation import body_stability
from flexmech.service.solvers.equilibrium import NewtonOptions, newton

OPTIONS = NewtonOptions(max_iterations=200, tol_residual=1e-11)


def _accept(mech, p, z_from, slot, value, jump):
    q = p.copy()
    q[slot] = value
    result = newton(mech, q, z_from, OPTIONS)
    moved = np.abs(result.z - z_from)[: mech.n_body_coordinates].max(initial=0.0)
    if not result.converged or moved > jump:
        return None
    K = np.asarray(mech.graphs.residual_and_tangent(result.z, q)[1])
    return result.z if body_stability(mech, K).stable else None


def natural_limit(
    mech, path: str, start: float, step: float, z0=None, jump: float = 0.02, rel_tol: float = 1e-11
) -> float:
    """The value of `path` (document units) where the stable branch through `start` ends when
    the field moves by `step` at a time: bisection between the last accepted and the first
    rejected value."""
    slot = mech.parameter_index(path)
    factor = mech.nd_per_doc(mech.parameters[slot].kind)
    p = mech.p()
    z = np.zeros(mech.n_free) if z0 is None else np.asarray(z0, dtype=float)
    good, bad = start * factor, None
    z = _accept(mech, p, z, slot, good, np.inf)
    assert z is not None, "no stable equilibrium at the start"
    while bad is None:
        trial = good + step * factor
        z_trial = _accept(mech, p, z, slot, trial, jump)
        if z_trial is None:
            bad = trial
        else:
            good, z = trial, z_trial
    while abs(bad - good) > rel_tol * abs(good):
        middle = (good + bad) / 2
        z_mid = _accept(mech, p, z, slot, middle, jump)
        if z_mid is None:
            bad = middle
        else:
            good, z = middle, z_mid
    return good / factor
