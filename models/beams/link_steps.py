"""A link's extrapolated steps (extrapolated_step), written out once per form of its
right-hand side and shared by every link, and every structure, with that form.

A link's right-hand side f(u, s, n, p) reads a few entries of the structure's parameter vector
p (its length, stiffnesses, shape). Written in those entries alone, q = p[used], in the order
they first appear, links of one kind (a straight link, an arc, one section type) have the
same right-hand side whatever their names and places in p, so they share one general step
(u0, s, n, q, H) -> s at u0 + H. Writing a step out costs 3-6 ms of CasADi's Python calls (a
large structure's links took 0.12-0.18 s of its first solve); calling it, a copy in C++.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass

import casadi as ca

KEPT = 256  # general steps kept per thread (a few hundred instructions each)
# Per thread: one Function object is not called from several threads (CasADi's rule)
_kept = threading.local()


@dataclass(frozen=True)
class LocalForm:
    """A right-hand side in its own parameters: f(u, s, n, p) = local(u, s, n, p[used])."""

    local: ca.Function
    used: list[int]
    key: str


def local_form(f: ca.Function) -> LocalForm:
    """f(u, s, n, p) written in the entries of p it reads, in the order they first appear."""
    u, s, n = (ca.SX.sym(f.name_in(i), f.sparsity_in(i)) for i in range(3))
    p = ca.SX.sym("p", f.sparsity_in(3))
    ds = f(u, s, n, p)
    index = {v.name(): i for i, v in enumerate(ca.vertsplit(p))}
    used = [index[v.name()] for v in ca.symvar(ds) if v.name() in index]
    q = ca.SX.sym("q", len(used))
    local_ds = ca.substitute(ds, ca.vertcat(*[p[i] for i in used]) if used else ca.SX(0, 1), q)
    local = ca.Function(f.name(), [u, s, n, q], [local_ds], ["u", "s", "n", "q"], f.name_out())
    return LocalForm(local, used, local.serialize())


def general_step(form: LocalForm, order: int) -> ca.Function:
    """(u0, s, n, q, H) -> s at u0 + H for the form's right-hand side, written out once per
    thread."""
    key = (form.key, order)
    if not hasattr(_kept, "steps"):
        _kept.steps = OrderedDict()
    kept: OrderedDict = _kept.steps
    found = kept.get(key)
    if found is not None:
        kept.move_to_end(key)
        return found
    f = form.local
    u0, s, n, q = (ca.SX.sym(name, f.sparsity_in(i)) for i, name in enumerate(("u0", "s", "n", "q")))
    H = ca.SX.sym("H")
    step = ca.Function(
        "link_general_step",
        [u0, s, n, q, H],
        [extrapolated_step(f, u0, s, H, order, n, q)],
        ["u0", "s", "n", "q", "H"],
        ["s_end"],
    )
    kept[key] = step
    while len(kept) > KEPT:
        kept.popitem(last=False)
    return step


def extrapolated_step(f: ca.Function, u0, s0, H, order: int, n, p) -> ca.SX:
    """s at u0 + H from s0: modified midpoint with 2, 4, ..., order substeps, extrapolated
    to h = 0 by Aitken-Neville in h^2 (Gragg's error expansion); error O(H^(order+1))."""
    levels = order // 2
    steps = [2 * (j + 1) for j in range(levels)]
    table: list[list[ca.SX]] = []
    slope0 = f(u0, s0, n, p)  # every sequence starts with it: written once
    for j, count in enumerate(steps):
        h = H / count
        previous, current = s0, s0 + h * slope0
        for i in range(1, count):
            previous, current = current, previous + 2 * h * f(u0 + i * h, current, n, p)
        row = [current]
        for k in range(1, j + 1):
            ratio = (steps[j] / steps[j - k]) ** 2
            row.append(row[k - 1] + (row[k - 1] - table[j - 1][k - 1]) / (ratio - 1))
        table.append(row)
    return table[-1][-1]
