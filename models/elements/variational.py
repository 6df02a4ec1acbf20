"""The residual form of an element that is stated by an energy: V(d, q) with equalities
g(d, q) = 0, its own variables q, and the equalities' multipliers lam.

Its unknowns in z are [q; lam]; its rows are the gradient of the Lagrangian
L = V + lam . g in q, then g; the wrench body b applies to it is dL/dd_b (the contract of
models.elements.base). So its residual form is the stationarity of its energy form, by
construction.
"""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca

from flexmech.models.elements.base import EnergyTerms


def variational_parts(
    bodies: tuple[int, ...],
    n_bodies: int,
    d: list[ca.SX],
    z: ca.SX,
    build: Callable[[list[ca.SX]], tuple[EnergyTerms, list[ca.SX]]],
) -> tuple[dict[int, ca.SX], ca.SX, ca.SX, list[ca.SX]]:
    """(wrench of each listed body on the element, rows, energy, extras) for unknowns z.
    build(d) states the element for body displacements d: its EnergyTerms (with `variables`
    its own symbols q) and extra expressions (outputs, drawing) to evaluate at z as well."""
    symbols = {b: ca.SX.sym(f"d{b}", 3) for b in bodies}
    local = [symbols.get(b, d[b]) for b in range(n_bodies)]
    terms, extras = build(local)
    q = terms.variables if terms.variables is not None else ca.SX(0, 1)
    g = ca.vertcat(*[row for _, row in terms.equalities]) if terms.equalities else ca.SX(0, 1)
    lam = z[q.numel() :]
    lagrangian = terms.energy + ca.dot(lam, g)
    rows = ca.vertcat(ca.gradient(lagrangian, q), g)
    wrenches = [ca.gradient(lagrangian, symbols[b]) for b in bodies]
    old = ca.vertcat(q, *[symbols[b] for b in bodies])
    new = ca.vertcat(z[: q.numel()], *[d[b] for b in bodies])
    values = ca.substitute([rows, terms.energy, *wrenches, *extras], [old], [new])
    rows, energy, wrenches, extras = values[0], values[1], values[2 : 2 + len(bodies)], values[2 + len(bodies) :]
    return dict(zip(bodies, wrenches)), rows, energy, list(extras)
