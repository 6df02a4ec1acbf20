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

from models.assembly import _Builder
from models.link import LinkShooting, inverse_rhs_function
from models.mechanism import Structure
from models.planar import cross, rot


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

    psi: tuple[PsiLayout, ...]  # per link, in structure.links order
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


class _InverseBuilder(_Builder):
    def __init__(self, structure: Structure, layout: InverseLayout):
        super().__init__(structure)
        self.layout = layout
        self.q = ca.SX.sym("q", layout.q_size)
        n_loads = len(layout.unknown_loads)
        self.n = structure.n_unknowns + n_loads
        self.z = ca.SX.sym("z", self.n)
        # the parameter vector with the unknown loads taken from z
        p_list = [self.p[i] for i in range(self.p.numel())]
        for k, index in enumerate(layout.unknown_loads):
            p_list[index] = self.z[structure.n_unknowns + k]
        self.p_eff = ca.vertcat(*p_list)
        self.psi_builders = []
        offset = 0
        for layout_k in layout.psi:
            data = self.q[offset:offset + layout_k.size]
            offset += layout_k.size
            matrix = ca.DM(layout_k.to_chebyshev())
            coefficients = matrix @ data
            self.psi_builders.append(
                lambda u, c=coefficients: chebyshev_series([c[i] for i in range(c.numel())], 2 * u - 1))
        self.specified_values = self.q[offset:]

    def build(self) -> InverseGraphs:
        s = self.s
        z = self.z
        # Loads as unknowns: substitute them into every parameter-dependent expression.
        d = self.displacements(z)
        rotations = [ca.vertcat(0, 0, d[b][2]) for b in range(self.nb)]
        el, _ = self.elastic(rotations, rotations, rotations)
        rows, names, kinds, values = [], [], [], []
        for k, (link, forward, undeformed, offset) in enumerate(zip(s.links, self.shooting, self.undeformed,
                                                                    s.link_offsets)):
            inverse = LinkShooting(forward.props, self.p, link.intervals, link.order,
                                   inverse_rhs_function(forward.props, self.psi_builders[k], self.p, self.q),
                                   ca.vertcat(self.p, self.q))
            psi = self.psi_builders[k]
            zl = z[offset:offset + link.unknowns]
            i, j = link.start_body, link.end_body
            (ri_hat, thi_hat), (rj_hat, thj_hat) = self.reference(i), self.reference(j)
            s_i = rot(thi_hat).T @ (undeformed[0][2:4] - ri_hat)
            s_j = rot(thj_hat).T @ (undeformed[-1][2:4] - rj_hat)
            start_xy = ri_hat + d[i][:2] + rot(thi_hat) @ s_i  # undeformed: shifted, not rotated
            end_xy = rj_hat + d[j][:2] + rot(thj_hat) @ s_j
            sol = inverse.solve_nodes(zl, start_xy, undeformed)
            end = sol.nodes[-1]
            psi0, psi1 = ca.SX(psi(ca.SX(0.0))), ca.SX(psi(ca.SX(1.0)))
            start_row = psi0 - sol.nodes[0][0] - d[i][2] if link.start == "clamped" else zl[3]
            end_row = psi1 - end[0] - d[j][2] if link.end == "clamped" else end[1]
            rows.append(ca.vertcat(start_row, *sol.continuity, end[2:4] - end_xy, end_row))
            n = ca.vertcat(zl[0], zl[1])
            arm_i, arm_j = rot(thi_hat + d[i][2]) @ s_i, rot(thj_hat + d[j][2]) @ s_j
            el[i] = el[i] + ca.vertcat(-n, -zl[3] + cross(arm_i, -n))
            el[j] = el[j] + ca.vertcat(n, end[1] + cross(arm_j, n))
            for q_name, kind, value in (("h", "force", zl[0]), ("v", "force", zl[1]),
                                        ("M_start", "moment", zl[3]), ("M_end", "moment", end[1]),
                                        ("energy", "energy", sol.energy)):
                names.append(f"elements.{link.name}.{q_name}")
                kinds.append(kind)
                values.append(value)
            for node, state in enumerate(sol.nodes):
                for q_name, kind, value in (("eta", "angle", state[0]), ("x0", "length", state[2]),
                                            ("y0", "length", state[3])):
                    names.append(f"elements.{link.name}.{q_name}.{node}")
                    kinds.append(kind)
                    values.append(value)
        applied = self.applied(rotations)
        body_rows = self.free_rows([el[b] - applied[b] for b in range(self.nb)])
        specified_rows = [z[s.link_offsets[link]] if component == 0 else z[s.link_offsets[link] + 1]
                          for link, component in self.layout.specified]
        specified_rows = [row - self.specified_values[k] for k, row in enumerate(specified_rows)]
        R = ca.vertcat(body_rows, *rows, *specified_rows)
        R = ca.substitute(R, self.p, self.p_eff)
        values = [ca.substitute(v, self.p, self.p_eff) for v in values]
        for b, body in enumerate(s.bodies):
            r_hat, th_hat = self.reference(b)
            for q_name, kind, value in (("x0", "length", r_hat[0] + d[b][0]), ("y0", "length", r_hat[1] + d[b][1]),
                                        ("rotation", "angle", d[b][2])):
                names.append(f"bodies.{body}.{q_name}")
                kinds.append(kind)
                values.append(value)
        K = ca.jacobian(R, z)
        inputs, labels = [z, self.p, self.q], ["z", "p", "q"]
        residual_and_tangent = ca.Function("link_inverse", inputs, [R, K], labels, ["R", "K"], dict(cse=True))
        results = ca.Function("link_inverse_results", inputs, [ca.vertcat(*values)], labels, ["y"], dict(cse=True))
        for f in (residual_and_tangent, results):
            if f.has_free():
                raise RuntimeError(f"graph {f.name()} has free symbols {f.get_free()}")
        return InverseGraphs(residual_and_tangent, results, tuple(names), tuple(kinds), self.n)


@lru_cache(maxsize=16)
def inverse_graphs_for(structure: Structure, layout: InverseLayout) -> InverseGraphs:
    return _InverseBuilder(structure, layout).build()
