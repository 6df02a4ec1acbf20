"""Robust design: objectives and constraints on mean + k sigma of an output, and on the first-order
yield against the document's tolerance specs, with exact gradients.

First order at a load case's equilibrium z(p): the toleranced parameters move by L xi (xi the
standardized sources, L their loadings, service.tolerances.fields), so the output y moves by
  dy/dxi = y_z S + y_p L,   K S + R_p L = 0   (K = dR/dz, R_p = dR/dp),
its mean is its nominal value and sigma = |dy/dxi| (a uniform source counts by its standard
deviation). A robust output is mean + k sigma (k signed: an upper bound and a minimized objective
take +k, a lower bound and a maximized objective -k). The yield is the product over the specs of
P(min <= y <= max) for y normal(mean, sigma): the specs taken as independent (outputs that move
with the same source fail together, so the product is then a lower bound of the first-order share
that meets them all). In the design NLP S is an unknown block of its own, with K S + R_p L = 0 as
equality rows (service.design.robust_nlp): sparse, and IPOPT gets exact derivatives through the
design variables, the state and S. Here: the terms (y, K, R_p L, y_z, y_p L) of a case, the
numbers at a state, and the formulas on (y, dy/dxi) that the NLP and the reports share."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.units import quantity_to_si

TAIL = -3.0  # where ln Phi changes from erf to the tail's continued fraction
TAIL_LEVELS = 40  # of the continued fraction
TINY = 1e-30  # in sigma^2 (nondimensional): sigma stays differentiable where no field moves it


@dataclass(frozen=True)
class Robustness:
    """The scatter as the NLP needs it: per toleranced parameter (slot) its loading on each
    independent source (nondimensional), and the specs (output index, low, high; nondimensional)."""

    slots: tuple[int, ...]
    loadings: tuple[tuple[float, ...], ...]  # slots x sources
    specs: tuple[tuple[int, float, float], ...] = ()

    @property
    def scatter(self) -> tuple:
        """What the first-order terms depend on (not the specs)."""
        return self.slots, self.loadings

    @property
    def n_sources(self) -> int:
        return len(self.loadings[0])


def robustness(mech: Mechanism, here: str, with_specs: bool = False) -> Robustness:
    """The document's tolerances for a robust objective or constraint named at `here`."""
    from flexmech.service.tolerances.fields import resolve_scatter

    spec = mech.document.tolerances
    if spec is None:
        raise MechanismError(here, "a robust objective or constraint needs the document's tolerances section")
    scatter = resolve_scatter(mech, spec)
    factors = np.array([mech.nd_per_doc(f.kind) for f in scatter.fields])
    loadings = scatter.loadings() * factors[:, None]
    specs = _specs(mech, spec, here) if with_specs else ()
    return Robustness(tuple(scatter.slots), tuple(map(tuple, loadings.tolist())), specs)


def _specs(mech: Mechanism, spec, here: str) -> tuple[tuple[int, float, float], ...]:
    names, kinds = mech.graphs.output_names, mech.graphs.output_kinds
    out = []
    for key, limits in spec.specs.items():
        where = "/tolerances/specs/" + key.replace("~", "~0").replace("/", "~1")
        if key not in names:
            raise MechanismError(
                where,
                f"'{key}' is not an output: a yield in design counts the specs on outputs (a target's field or a "
                "frequency is for the tolerance analysis)",
            )
        k = names.index(key)
        kind, unit = kinds[k], mech.doc_unit(kinds[k])
        bounds = []
        for name, given in (("min", limits.min), ("max", limits.max)):
            value = -np.inf if name == "min" else np.inf
            if given is not None:
                value = (
                    quantity_to_si(given, kind, unit, f"{where}/{name}") / mech.doc_factor(kind) * mech.nd_per_doc(kind)
                )
            bounds.append(value)
        out.append((k, float(bounds[0]), float(bounds[1])))
    if not out:
        raise MechanismError(here, "a yield needs specs on outputs in the tolerances section")
    return tuple(out)


@lru_cache(maxsize=16)
def first_order_terms(structure, scatter: tuple) -> ca.Function:
    """(z, p) -> (y, K, R_p L, y_z, y_p L) of a structure and a scatter (Robustness.scatter):
    the outputs, the tangent, and the terms of K S + R_p L = 0 and dy/dxi = y_z S + y_p L."""
    from flexmech.models.graph.assembly import graphs_for

    slots, loadings = scatter
    graphs = graphs_for(structure)
    z = ca.SX.sym("z", structure.n_unknowns)
    p = ca.SX.sym("p", len(structure.parameters))
    R, y = graphs.residual(z, p), graphs.outputs(z, p)
    L = ca.DM.zeros(len(structure.parameters), len(loadings[0]))
    for row, slot in enumerate(slots):
        L[slot, :] = ca.DM(loadings[row]).T
    terms = ca.Function(
        "first_order_terms",
        [z, p],
        [y, ca.jacobian(R, z), ca.mtimes(ca.jacobian(R, p), L), ca.jacobian(y, z), ca.mtimes(ca.jacobian(y, p), L)],
        ["z", "p"],
        ["y", "K", "R_pL", "y_z", "y_pL"],
        dict(cse=True),
    )
    if terms.has_free():
        raise RuntimeError(f"graph first_order_terms has free symbols {terms.get_free()}")
    return terms


def first_order(structure, robust: Robustness, z: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(y, dy/dxi) at an equilibrium (z, p): every output and its move per source's standard
    deviation (nondimensional; outputs x sources)."""
    y, K, R_pL, y_z, y_pL = (np.asarray(a, dtype=float) for a in first_order_terms(structure, robust.scatter)(z, p))
    S = -np.linalg.solve(K, R_pL)
    return y.ravel(), y_z @ S + y_pL


def spread(moves):
    """sigma of an output from its row of dy/dxi: smooth where nothing moves it."""
    return ca.sqrt(ca.sumsqr(moves) + TINY)


def robust_output(y, moves, index: int, sigmas: float):
    """mean + sigmas * sigma of output `index` (sigmas signed)."""
    return y[index] + sigmas * spread(moves[index, :])


def log_yield(y, moves, specs) -> ca.SX | ca.DM:
    """ln of the product over the specs of the normal share within their bounds: the logarithm
    keeps a slope where the share is a tail of 1e-17 (a start far from the specs)."""
    total = 0
    for index, low, high in specs:
        total = total + log_share(y[index], spread(moves[index, :]), low, high)
    return total


def log_share(mean, sigma, low: float, high: float):
    """ln P(low <= y <= high) for y normal(mean, sigma). Two-sided, as Phi(far) (1 - Phi(near) /
    Phi(far)) on the side away from the mean (mirrored when the mean is below the middle), so
    that neither difference of two shares near one loses its digits."""
    if not np.isfinite(low):
        return log_phi((high - mean) / sigma) if np.isfinite(high) else 0
    if not np.isfinite(high):
        return log_phi((mean - low) / sigma)
    a, b = (low - mean) / sigma, (high - mean) / sigma
    below = mean < (low + high) / 2
    far, near = ca.if_else(below, -a, b), ca.if_else(below, -b, a)
    top = log_phi(far)
    return top + ca.log(-ca.expm1(log_phi(near) - top))


def log_phi(x):
    """ln Phi(x), the standard normal's, to about 1e-13 for every x: by erf down to x = -3 (where
    1 + erf keeps 13 digits), below as ln(phi(x) R(-x)) with Mills' ratio R(t) by Laplace's
    continued fraction 1 / (t + 1 / (t + 2 / (t + ...))) of TAIL_LEVELS levels (1e-14 at t = 3,
    better beyond), each branch clamped to its side so that neither makes an infinity or a NaN."""
    above = x >= TAIL
    near = ca.log(0.5 * (1 + ca.erf(ca.if_else(above, x, TAIL) / np.sqrt(2))))
    t = -ca.if_else(above, TAIL, x)
    fraction = t
    for level in range(TAIL_LEVELS, 0, -1):
        fraction = t + level / fraction
    far = -(t**2) / 2 - np.log(np.sqrt(2 * np.pi)) - ca.log(fraction)
    return ca.if_else(above, near, far)


def robust_value(structure, ref, z: np.ndarray, p: np.ndarray) -> float:
    """A robust output's value at an equilibrium (z, p) as the NLP holds it: mean + k sigma
    (nondimensional), or the yield's logarithm."""
    y, moves = first_order(structure, ref.robust, z, p)
    y, moves = ca.DM(y), ca.DM(moves)
    if ref.source == "yield":
        return float(log_yield(y, moves, ref.robust.specs))
    return float(robust_output(y, moves, ref.index, ref.sigmas))
