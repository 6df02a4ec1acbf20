"""Inverse kinetostatic analysis: the wrenches that hold a given configuration (closed form)."""

from __future__ import annotations

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.service.units import wrench_to_doc

_KINDS = ("length", "length", "angle")


def inverse_wrenches(mech: Mechanism, displacements: dict[str, tuple[float, float, float]]) -> dict[str, np.ndarray]:
    """Wrench [Fx, Fy, M about the reference point] each body needs from outside (loads plus
    supports) to stay in the configuration where every body is displaced by
    displacements[body] = (dx, dy, rotation) in document units (absent bodies: not moved).

    No iteration: it evaluates the elastic wrenches of the flexures in that configuration.
    Links are distributed: their shape between given ends is itself an equilibrium problem,
    so they take the link inverse (service.solvers.inverse_links) instead.
    """
    owning = [t.name for t in mech.structure.elements if t.unknowns]
    if owning:
        raise MechanismError(
            "/displacements",
            "the closed-form inverse holds for elements whose forces follow "
            "from the body motions (curved beams with the linear or partial_nonlinear model, "
            f"springs); these elements have unknowns of their own: {', '.join(owning)} "
            "(links take the link inverse)",
        )
    bodies = mech.structure.bodies
    d = np.zeros(3 * len(bodies))
    for name, values in displacements.items():
        if name not in bodies:
            raise MechanismError(f"/displacements/{name}", f"unknown body '{name}' (bodies: {', '.join(bodies)})")
        if len(values) != 3:
            raise MechanismError(f"/displacements/{name}", "expected [dx, dy, rotation]")
        if not all(np.isfinite(values)):
            raise MechanismError(f"/displacements/{name}", "displacements must be finite numbers")
        b = bodies.index(name)
        d[3 * b : 3 * b + 3] = [v * mech.nd_per_doc(k) for v, k in zip(values, _KINDS)]
    elastic, _ = mech.graphs.body_wrenches(d, mech.p())
    w = wrench_to_doc(mech, np.asarray(elastic).ravel())
    return {name: w[b] for b, name in enumerate(bodies)}


def configuration_of(mech: Mechanism, z: np.ndarray) -> dict[str, tuple[float, float, float]]:
    """Body displacements (document units) of a solution z, including prescribed motions."""
    d = np.asarray(mech.graphs.displacements(z, mech.p())).ravel()
    out = {}
    for b, name in enumerate(mech.structure.bodies):
        out[name] = tuple(d[3 * b + c] / mech.nd_per_doc(k) for c, k in enumerate(_KINDS))
    return out
