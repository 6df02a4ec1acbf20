"""The inverse problem of a link network (seed 002, Sec. 5.2.3 and 5.3): given the deformed
angle psi(u) of every link and some internal forces, find the initial shapes eta(u) and the
unknown external loads.

Unknowns z (nondimensional), in order:
  - per free body coordinate: for x and y the shift of the body's *undeformed* position
    from the document's, for the angle the body's rotation under load;
  - per link, as in the forward problem but with eta in place of psi: h, v, d eta(0), m(0)
    and (d eta, m, dx0, dy0) at the inner shooting nodes, as deviations from the document's
    initial shape (which is therefore the starting guess);
  - the unknown load components.
Equations: the bodies' balance in the deformed configuration (Eqs. 5.2a,b and 5.3b), the
links' shooting and end conditions on the undeformed centre line (5.2c-h) and the angles
psi - eta = body rotation at clamped ends (5.3a,d), m = 0 at pins (5.3c,e), and one
equation per specified internal force. The count is square when as many internal force
components are given as load components are unknown (Sec. 5.3.2).

Each link's psi(u) is a Chebyshev series in 2u - 1 whose coefficients are a fixed linear
map of the data (polynomial coefficients, or samples at given u): the data are inputs q of
the graph, so one graph serves any data of the same layout.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from flexmech.models.beams.link_shooting import LinkShooting, inverse_rhs_function
from flexmech.models.elements import FAMILIES
from flexmech.models.elements.base import Contribution
from flexmech.models.elements.link import LinkTopology, link_shooting
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.loads import applied_wrenches
from flexmech.models.graph.planar import cross, rot
from flexmech.models.graph.residual import residual_of
from flexmech.models.graph.structure import Structure


@dataclass(frozen=True)
class PsiLayout:
    """How one link's psi data map to Chebyshev coefficients: 'polynomial' with `size`
    monomial coefficients, or 'samples' at the positions `at` (degree len(at) - 1)."""

    kind: str
    size: int
    at: tuple[float, ...] = ()

    def to_chebyshev(self) -> np.ndarray:
        """Matrix (size x size): Chebyshev coefficients of psi from the data."""
        n = self.size
        if self.kind == "polynomial":
            # monomials u^k with u = (t + 1) / 2, as Chebyshev series in t
            matrix = np.zeros((n, n))
            for k in range(n):
                monomial = np.polynomial.Polynomial([0.5, 0.5]) ** k  # u as a polynomial in t
                matrix[:, k] = np.pad(np.polynomial.chebyshev.poly2cheb(monomial.coef), (0, n - k - 1))[:n]
            return matrix
        t = 2 * np.asarray(self.at, dtype=float) - 1
        vandermonde = np.polynomial.chebyshev.chebvander(t, n - 1)
        return np.linalg.inv(vandermonde)


@dataclass(frozen=True)
class InverseLayout:
    """The structure of one inverse problem; numbers go in q."""

    psi: tuple[PsiLayout, ...]  # per link, in document order
    unknown_loads: tuple[int, ...]  # parameter indices that become unknowns
    specified: tuple[tuple[int, int], ...]  # (link index, 0 for h / 1 for v)

    @property
    def q_size(self) -> int:
        return sum(layout.size for layout in self.psi) + len(self.specified)


def chebyshev_series(coefficients: list[ca.SX], t: ca.SX) -> ca.SX:
    """sum c_k T_k(t) by Clenshaw's recurrence (a polynomial: smooth at t = +-1)."""
    b1, b2 = ca.SX(0), ca.SX(0)
    for c in reversed(coefficients[1:]):
        b1, b2 = c + 2 * t * b1 - b2, b1
    return coefficients[0] + t * b1 - b2


@dataclass(frozen=True)
class InverseGraphs:
    residual_and_tangent: ca.Function  # (z, p, q) -> (R, K)
    results: ca.Function  # (z, p, q) -> y
    result_names: tuple[str, ...]
    result_kinds: tuple[str, ...]
    n_unknowns: int


def _psi_builders(layout: InverseLayout, q: ca.SX) -> list:
    """psi(u) of every link, a Chebyshev series whose coefficients are linear in the data q."""
    builders, offset = [], 0
    for layout_k in layout.psi:
        data = q[offset : offset + layout_k.size]
        offset += layout_k.size
        coefficients = ca.DM(layout_k.to_chebyshev()) @ data
        builders.append(lambda u, c=coefficients: chebyshev_series([c[i] for i in range(c.numel())], 2 * u - 1))
    return builders


def _inverse_link(ctx: AssemblyContext, t: LinkTopology, psi, q: ca.SX, d, zl):
    """A link's rows on its undeformed centre line (its deformed angle psi given), the
    wrenches its bodies apply to it, and its reported values."""
    forward = link_shooting(ctx, t)
    undeformed = forward.undeformed_nodes()
    inverse = LinkShooting(
        forward.props,
        ctx.p,
        t.intervals,
        t.order,
        inverse_rhs_function(forward.props, psi, ctx.p, q),
        ca.vertcat(ctx.p, q),
    )
    i, j = t.start_body, t.end_body
    s_i, s_j = ctx.body_axes(i, undeformed[0][2:4]), ctx.body_axes(j, undeformed[-1][2:4])
    start_xy = ctx.reference(i)[0] + d[i][:2] + rot(ctx.reference(i)[1]) @ s_i  # undeformed: shifted, not rotated
    end_xy = ctx.reference(j)[0] + d[j][:2] + rot(ctx.reference(j)[1]) @ s_j
    sol = inverse.solve_nodes(zl, start_xy, undeformed)
    end = sol.nodes[-1]
    psi0, psi1 = ca.SX(psi(ca.SX(0.0))), ca.SX(psi(ca.SX(1.0)))
    start_row = psi0 - sol.nodes[0][0] - d[i][2] if t.start == "clamped" else zl[3]
    end_row = psi1 - end[0] - d[j][2] if t.end == "clamped" else end[1]
    rows = ca.vertcat(start_row, *sol.continuity, end[2:4] - end_xy, end_row)
    n = ca.vertcat(zl[0], zl[1])
    arm_i, arm_j = ctx.arm(i, s_i, d), ctx.arm(j, s_j, d)
    wrenches = {i: ca.vertcat(-n, -zl[3] + cross(arm_i, -n)), j: ca.vertcat(n, end[1] + cross(arm_j, n))}
    values = [
        ("h", "force", zl[0]),
        ("v", "force", zl[1]),
        ("M_start", "moment", zl[3]),
        ("M_end", "moment", end[1]),
        ("energy", "energy", sol.energy),
    ]
    for node, state in enumerate(sol.nodes):
        values += [
            (f"eta.{node}", "angle", state[0]),
            (f"x0.{node}", "length", state[2]),
            (f"y0.{node}", "length", state[3]),
        ]
    return Contribution(wrenches, rows, values)


def _invertible(t) -> bool:
    """Whether the inverse solves the element's shape (its family says: links by shooting)."""
    return getattr(FAMILIES.of(t), "invertible", False)


def _build(structure: Structure, layout: InverseLayout) -> InverseGraphs:
    ctx = AssemblyContext(structure)
    q = ca.SX.sym("q", layout.q_size)
    n_loads = len(layout.unknown_loads)
    n = structure.n_unknowns + n_loads
    z = ca.SX.sym("z", n)
    # The unknown loads are taken from z: substituted into every parameter-dependent expression.
    p_list = [ctx.p[i] for i in range(ctx.p.numel())]
    for k, index in enumerate(layout.unknown_loads):
        p_list[index] = z[structure.n_unknowns + k]
    p_eff = ca.vertcat(*p_list)
    d = ctx.displacements(z)
    rotations = [ca.vertcat(0, 0, d[b][2]) for b in range(ctx.n_bodies)]
    psi_builders = iter(_psi_builders(layout, q))
    parts, names, kinds, values = [], [], [], []
    for t, offset in zip(structure.elements, structure.element_offsets):
        if _invertible(t):
            part = _inverse_link(ctx, t, next(psi_builders), q, d, z[offset : offset + t.unknowns])
            for quantity, kind, value in part.outputs:
                names.append(f"elements.{t.name}.{quantity}")
                kinds.append(kind)
                values.append(value)
        else:
            part = FAMILIES.of(t).contribute(ctx, t, rotations, ca.SX(0, 1))
            part = Contribution(part.from_bodies)
        parts.append(part)
    links = [k for k, t in enumerate(structure.elements) if _invertible(t)]
    specified_values = q[layout.q_size - len(layout.specified) :]
    specified_rows = [
        z[structure.element_offsets[links[link]] + component] - specified_values[k]
        for k, (link, component) in enumerate(layout.specified)
    ]
    R = ca.vertcat(residual_of(ctx, parts, applied_wrenches(ctx, rotations)), *specified_rows)
    R = ca.substitute(R, ctx.p, p_eff)
    values = [ca.substitute(v, ctx.p, p_eff) for v in values]
    for b, body in enumerate(structure.bodies):
        r_hat, th_hat = ctx.reference(b)
        for q_name, kind, value in (
            ("x0", "length", r_hat[0] + d[b][0]),
            ("y0", "length", r_hat[1] + d[b][1]),
            ("rotation", "angle", d[b][2]),
        ):
            names.append(f"bodies.{body}.{q_name}")
            kinds.append(kind)
            values.append(value)
    K = ca.jacobian(R, z)
    inputs, labels = [z, ctx.p, q], ["z", "p", "q"]
    residual_and_tangent = ca.Function("link_inverse", inputs, [R, K], labels, ["R", "K"], dict(cse=True))
    results = ca.Function("link_inverse_results", inputs, [ca.vertcat(*values)], labels, ["y"], dict(cse=True))
    for f in (residual_and_tangent, results):
        if f.has_free():
            raise RuntimeError(f"graph {f.name()} has free symbols {f.get_free()}")
    return InverseGraphs(residual_and_tangent, results, tuple(names), tuple(kinds), n)


@lru_cache(maxsize=16)
def inverse_graphs_for(structure: Structure, layout: InverseLayout) -> InverseGraphs:
    return _build(structure, layout)
