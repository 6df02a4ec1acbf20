"""Robust design: objectives and constraints on mean + k sigma of an output, and on the first-order
yield against the document's tolerance specs, with exact gradients.

First order at a load case's equilibrium z(p): the toleranced parameters move by L xi (xi the
standardized sources, L their loadings, service.tolerances.fields), so the output y moves by
  dy/dxi = y_z S + y_p L,   K S = -R_p L   (K = dR/dz),
its mean is its nominal value and sigma = |dy/dxi|. A robust output is mean + k sigma (k signed:
an upper bound and a minimized objective take +k, a lower bound and a maximized objective -k).
The yield is the product over the specs of P(min <= y <= max) for y normal(mean, sigma): the
specs taken as independent, which over-counts the failures of outputs that move together (a
lower bound on the true yield when they fail together). All of it is one CasADi graph of the
case's (z, p), so IPOPT gets its exact derivatives through the design variables and the state;
the loadings and spec bounds are constants of the graph (the design NLP is built per structure,
scatter and specs: service.design.nlp's key)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.units import quantity_to_si

TAIL = -7.0  # where ln Phi changes from erf to the asymptotic series
TINY = 1e-30  # in sigma^2 (nondimensional): sigma stays differentiable where no field moves it


@dataclass(frozen=True)
class Robustness:
    """The scatter as the NLP needs it: per toleranced parameter (slot) its loading on each
    independent source (nondimensional), and the specs (output index, low, high; nondimensional)."""

    slots: tuple[int, ...]
    loadings: tuple[tuple[float, ...], ...]  # slots x sources
    specs: tuple[tuple[int, float, float], ...] = ()


def robustness(mech: Mechanism, here: str, with_specs: bool = False) -> Robustness:
    """The document's tolerances for a robust objective or constraint named at `here`."""
    from flexmech.service.tolerances.fields import resolve_scatter

    spec = mech.document.tolerances
    if spec is None:
        raise MechanismError(here, "a robust objective or constraint needs the document's tolerances section")
    try:
        scatter = resolve_scatter(mech, spec)
    except MechanismError as exc:
        raise MechanismError(exc.pointer, exc.problem) from None
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
            raise MechanismError(where, f"'{key}' is not an output: a yield in design counts the outputs' specs")
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
def _first_order(structure, robust: Robustness) -> ca.Function:
    """(z, p) -> (y, dy/dxi): every output and its move per source's standard deviation."""
    from flexmech.models.graph.assembly import graphs_for

    graphs = graphs_for(structure)
    z = ca.SX.sym("z", structure.n_unknowns)
    p = ca.SX.sym("p", len(structure.parameters))
    R, y = graphs.residual(z, p), graphs.outputs(z, p)
    L = ca.DM.zeros(len(structure.parameters), len(robust.loadings[0]))
    for row, slot in enumerate(robust.slots):
        L[slot, :] = ca.DM(robust.loadings[row]).T
    S = -ca.solve(ca.jacobian(R, z), ca.mtimes(ca.jacobian(R, p), L))
    moves = ca.mtimes(ca.jacobian(y, z), S) + ca.mtimes(ca.jacobian(y, p), L)
    return ca.Function("first_order_scatter", [z, p], [y, moves])


def sigma(structure, robust: Robustness, z, p, index: int):
    """(mean, sigma) of output `index` at the case's (z, p), nondimensional."""
    y, moves = _first_order(structure, robust)(z, p)
    return y[index], ca.sqrt(ca.sumsqr(moves[index, :]) + TINY)


def first_order_yield(structure, robust: Robustness, z, p):
    """ln of the product over the specs of the normal share within their bounds: the logarithm
    keeps a slope where the share is a tail of 1e-17 (a start far from the specs)."""
    y, moves = _first_order(structure, robust)(z, p)
    log_share = 0
    for index, low, high in robust.specs:
        mean, spread = y[index], ca.sqrt(ca.sumsqr(moves[index, :]) + TINY)
        upper = 0 if not np.isfinite(high) else log_phi((high - mean) / spread)
        if np.isfinite(low):  # Phi(b) - Phi(a) = Phi(b) (1 - Phi(a) / Phi(b))
            upper = upper + ca.log(1 - ca.exp(log_phi((low - mean) / spread) - upper))
        log_share = log_share + upper
    return log_share


def log_phi(x):
    """ln Phi(x), the standard normal's: by erf down to x = -7 (where 1 + erf keeps 1e-4 of its
    digits), below by the tail's asymptotic series (4 terms: 1e-4 at -7), each branch clamped to
    its side so that neither makes an infinity."""
    near = ca.log(0.5 * (1 + ca.erf(ca.fmax(x, TAIL) / np.sqrt(2))))
    t = -ca.fmin(x, TAIL)
    far = -(t**2) / 2 - ca.log(t * np.sqrt(2 * np.pi)) + ca.log(1 - 1 / t**2 + 3 / t**4 - 15 / t**6)
    return ca.if_else(x >= TAIL, near, far)


def robust_value(structure, ref, z: np.ndarray, p: np.ndarray) -> float:
    """A robust output's value at a state as the NLP holds it: mean + k sigma (nondimensional),
    or the yield's logarithm."""
    if ref.source == "yield":
        return float(first_order_yield(structure, ref.robust, z, p))
    mean, spread = sigma(structure, ref.robust, z, p, ref.index)
    return float(mean + ref.sigmas * spread)
