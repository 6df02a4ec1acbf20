"""Distributed elastica links (seed 002, Ch. 2 and 5): equations, integrator and shooting.

A link of length L runs from u = 0 to u = 1 with the initial tangent angle eta(u) (global
frame). Its state along u is s = (psi, m, x, y, e): the cross-section angle, the bending
moment, the centre-line position and the strain energy accumulated from the interval's
start. The internal force n = (h, v) (global frame) is constant along a link without
distributed load (Eq. 5.1b,c). Sign conventions: n(u) and m(u) are what the part beyond u
exerts on the part before it, so at u = 1 they are the end body's force and moment on the
link. With N = n . t, V = n . t_perp (t = (cos psi, sin psi)):

    psi' = eta'(u) + L m / EI(u)                      (Eq. 2.17 / 5.1a, m = EI (psi' - eta') / L)
    m'   = h y' - v x'                                (moment balance of a slice)
    x'   = L [(1 + N/EA) cos psi - (V/kGA) sin psi]   (axial strain: App. A.1; shear: Eq. 5.1)
    y'   = L [(1 + N/EA) sin psi + (V/kGA) cos psi]
    e'   = L [m^2 / 2EI + N^2 / 2EA + V^2 / 2kGA]

With shear on, this is Reissner's geometrically exact beam: the shear strain is V / kGA with V
normal to the cross-section. Eq. 5.1d of the thesis takes V normal to the deformed centre
line, which makes gamma implicit; the two agree to first order in gamma.

A link with mass (line mass L rho A(u) per unit u) carries a sixth state, its mass mu from
u = 0: mu' = L rho A. Under gravity g its own weight is a distributed load, and the internal
force falls along it, n(u) = n(0) - mu(u) g (a slice's balance: n' = -mu' g).

Each shooting interval is integrated by Gragg's modified midpoint rule extrapolated in h^2
(the fixed-order Gragg-Bulirsch-Stoer scheme): `order` = 2 x levels, explicit, so the whole
link is one SX graph with exact derivatives.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import casadi as ca

STATE = ("psi", "m", "x", "y", "e", "mu")  # mu only for links with mass


@dataclass(frozen=True)
class LinkProperties:
    """Symbolic description of one link (nondimensional), each field of u a builder."""

    length: ca.SX
    eta: Callable[[ca.SX], ca.SX]
    start_point: ca.SX  # (2,) undeformed position of u = 0, global
    EI: Callable[[ca.SX], ca.SX]
    EA: Callable[[ca.SX], ca.SX] | None  # None: inextensible
    kGA: Callable[[ca.SX], ca.SX] | None  # None: no shear strain
    fibre: Callable[[ca.SX], ca.SX] | None  # outer-fibre distance over I, for stresses; None: none
    half_thickness: Callable[[ca.SX], ca.SX] | None = None  # its surfaces' offset; None: unknown
    line_mass: Callable[[ca.SX], ca.SX] | None = None  # mass per unit u (L rho A); None: massless
    gravity: ca.SX | None = None  # (2,) acceleration, with line_mass: the link's own weight

    @property
    def states(self) -> int:
        """psi, m, x, y, e, and the mass mu from u = 0 when the link has mass."""
        return 6 if self.line_mass is not None else 5


def rhs_function(props: LinkProperties, p: ca.SX, weighed: bool = True) -> ca.Function:
    """f(u, s, n, p) -> s' for the state s (props.states) and the internal force n = (h, v)
    at u = 0; weighed (with gravity and a line mass), the force at u is n - mu(u) g: n less
    the weight of the part behind."""
    u, s, n_start = ca.SX.sym("u"), ca.SX.sym("s", props.states), ca.SX.sym("n", 2)
    psi, m = s[0], s[1]
    n = n_start
    if weighed and props.line_mass is not None and props.gravity is not None:
        n = n_start - s[5] * props.gravity
    h, v = n[0], n[1]
    L = props.length
    c, sn = ca.cos(psi), ca.sin(psi)
    N = h * c + v * sn
    V = -h * sn + v * c
    EI = props.EI(u)
    eps = N / props.EA(u) if props.EA is not None else 0
    gamma = V / props.kGA(u) if props.kGA is not None else 0
    dx = L * ((1 + eps) * c - gamma * sn)
    dy = L * ((1 + eps) * sn + gamma * c)
    u_eta = ca.SX.sym("u_eta")
    eta_slope = ca.substitute(ca.jacobian(ca.SX(props.eta(u_eta)), u_eta), u_eta, u)
    energy = m**2 / (2 * EI)
    if props.EA is not None:
        energy = energy + N**2 / (2 * props.EA(u))
    if props.kGA is not None:
        energy = energy + V**2 / (2 * props.kGA(u))
    ds = [eta_slope + L * m / EI, h * dy - v * dx, dx, dy, L * energy]
    if props.line_mass is not None:
        ds.append(props.line_mass(u))
    return ca.Function("link_rhs", [u, s, n_start, p], [ca.vertcat(*ds)], ["u", "s", "n", "p"], ["ds"])


def inverse_rhs_function(props: LinkProperties, psi: Callable[[ca.SX], ca.SX], p: ca.SX, q: ca.SX) -> ca.Function:
    """The inverse problem's equations (Eq. 5.4b, inextensible): the deformed angle psi(u) is
    given (a builder over the data q) and the state carries the initial shape instead,
    s = (eta, m, x0, y0, e) with (x0, y0) the undeformed centre line:

        eta' = psi'(u) - L m / EI(u),   m' = L (h sin psi - v cos psi),   x0' = L cos eta, ...
    """
    u, s, n = ca.SX.sym("u"), ca.SX.sym("s", 5), ca.SX.sym("n", 2)
    eta, m = s[0], s[1]
    h, v = n[0], n[1]
    L = props.length
    u_psi = ca.SX.sym("u_psi")
    psi_expr = ca.SX(psi(u_psi))
    angle = ca.substitute(psi_expr, u_psi, u)
    slope = ca.substitute(ca.jacobian(psi_expr, u_psi), u_psi, u)
    EI = props.EI(u)
    ds = ca.vertcat(slope - L * m / EI, L * (h * ca.sin(angle) - v * ca.cos(angle)),
                    L * ca.cos(eta), L * ca.sin(eta), L * m**2 / (2 * EI))
    return ca.Function("link_inverse_rhs", [u, s, n, ca.vertcat(p, q)], [ds], ["u", "s", "n", "p"], ["ds"])


def extrapolated_step(f: ca.Function, u0, s0, H, order: int, n, p) -> ca.SX:
    """s at u0 + H from s0: modified midpoint with 2, 4, ..., order substeps, extrapolated
    to h = 0 by Aitken-Neville in h^2 (Gragg's error expansion); error O(H^(order+1))."""
    levels = order // 2
    steps = [2 * (j + 1) for j in range(levels)]
    table: list[list[ca.SX]] = []
    for j, count in enumerate(steps):
        h = H / count
        previous, current = s0, s0 + h * f(u0, s0, n, p)
        for i in range(1, count):
            previous, current = current, previous + 2 * h * f(u0 + i * h, current, n, p)
        row = [current]
        for k in range(1, j + 1):
            ratio = (steps[j] / steps[j - k]) ** 2
            row.append(row[k - 1] + (row[k - 1] - table[j - 1][k - 1]) / (ratio - 1))
        table.append(row)
    return table[-1][-1]


@dataclass
class LinkSolution:
    """Symbolic node states of one link for given unknowns, and its end quantities."""

    nodes: list[ca.SX]  # deformed states at u_k = k / K, k = 0..K (the last one integrated)
    undeformed: list[ca.SX]  # undeformed states at the same nodes
    n: ca.SX  # (h, v)
    continuity: list[ca.SX]  # residual blocks, 4 each
    energy: ca.SX


class LinkShooting:
    """Multiple shooting of one link with K intervals: unknowns, residuals, samples."""

    def __init__(self, props: LinkProperties, p: ca.SX, intervals: int, order: int,
                 rhs: ca.Function | None = None, rhs_parameters: ca.SX | None = None):
        self.props = props
        self.p = p if rhs_parameters is None else rhs_parameters
        self.K = intervals
        self.order = order
        self.f = rhs_function(props, p) if rhs is None else rhs
        self.weighed = rhs is None and props.line_mass is not None and props.gravity is not None
        # The unloaded link: no internal force and no weight (its own weight is a load).
        self.f_unloaded = rhs_function(props, p, weighed=False) if self.weighed else self.f
        self.H = 1.0 / intervals
        self._steps: dict[tuple, ca.Function] = {}

    def step(self, k: int, s, n, H=None, u0=None, order=None, unloaded: bool = False):
        H = self.H if H is None else H
        u0 = k * self.H if u0 is None else u0
        return self._step_function(H, order or self.order, unloaded)(u0, s, n, self.p)

    def _step_function(self, H: float, order: int, unloaded: bool) -> ca.Function:
        """(u0, s, n, p) -> s at u0 + H: one extrapolated step written out once per step length
        and order, and called (inlined) at every node: the same expressions as writing out
        every step, built several times faster (a link's graph is mostly its steps)."""
        key = (H, order, unloaded)
        if key not in self._steps:
            f = self.f_unloaded if unloaded else self.f
            u0, s, n, p = (ca.SX.sym(name, f.sparsity_in(i)) for i, name in enumerate(("u0", "s", "n", "p")))
            self._steps[key] = ca.Function("link_step", [u0, s, n, p], [extrapolated_step(f, u0, s, H, order, n, p)])
        return self._steps[key]

    def _with_energy_reset(self, head: ca.SX, state: ca.SX) -> ca.SX:
        """(psi, m, x, y) `head`, the energy restarted at 0, and the mass carried over."""
        if self.props.states == 6:
            return ca.vertcat(head, 0, state[5])
        return ca.vertcat(head, 0)

    def undeformed_nodes(self) -> list[ca.SX]:
        """The unloaded link integrated node to node: with these as the reference, the
        unloaded state is an exact zero of the residual at any resolution."""
        zero = ca.SX.zeros(2)
        start = self.props.start_point
        s = ca.vertcat(ca.SX(self.props.eta(ca.SX(0.0))), 0, start[0], start[1], 0)
        if self.props.states == 6:
            s = ca.vertcat(s, 0)
        nodes = [s]
        for k in range(self.K):
            s = self.step(k, self._with_energy_reset(s[:4], s), zero, unloaded=True)
            nodes.append(s)
        return nodes

    def solve_nodes(self, zl: ca.SX, start_xy: ca.SX, undeformed: list[ca.SX]) -> LinkSolution:
        """Deformed node states from the link's unknowns zl = [h, v, dpsi0, m0, (dpsi, m, dx,
        dy) at nodes 1..K-1] (deviations from `undeformed`), the start at `start_xy`."""
        n = zl[0:2]
        nodes = [self._with_energy_reset(ca.vertcat(undeformed[0][0] + zl[2], zl[3], start_xy[0], start_xy[1]),
                                         undeformed[0])]
        for k in range(1, self.K):
            block = zl[4 * k:4 * k + 4]
            head = undeformed[k][:4] + ca.vertcat(block[0], block[1], block[2], block[3])
            nodes.append(self._with_energy_reset(head, undeformed[k]))
        continuity, energy = [], ca.SX(0)
        for k in range(self.K):
            end = self.step(k, nodes[k], n)
            energy = energy + end[4]
            if k + 1 < self.K:
                continuity.append(nodes[k + 1][:4] - end[:4])
            else:
                nodes.append(end)
        return LinkSolution(nodes, undeformed, n, continuity, energy)

    def internal_force(self, solution: LinkSolution, state: ca.SX) -> ca.SX:
        """The internal force (h, v) at a state along the link: n(0) less the weight behind."""
        if self.weighed:
            return solution.n - state[5] * self.props.gravity
        return solution.n

    def error_estimate(self, solution: LinkSolution) -> ca.SX:
        """Richardson estimate of the discretization error, relative to the link length: per
        interval, one step against two half steps from the converged node, summed."""
        total_position, total_angle = ca.SX(0), ca.SX(0)
        scale = 1 - 2.0 ** (-self.order)
        for k in range(self.K):
            s = solution.nodes[k]
            full = self.step(k, s, solution.n)
            half = self.step(k, s, solution.n, H=self.H / 2)
            half = self.step(k, half, solution.n, H=self.H / 2, u0=(k + 0.5) * self.H)
            diff = (full - half) / scale
            total_position = total_position + ca.norm_2(diff[2:4])
            total_angle = total_angle + ca.fabs(diff[0])
        return ca.fmax(total_position / self.props.length, total_angle)

    def samples(self, solution: LinkSolution, per_interval: int = 4) -> list[ca.SX]:
        """States along the link at per_interval points per shooting interval (plus u = 1)."""
        out = []
        H = self.H / per_interval
        for k in range(self.K):
            s = solution.nodes[k]
            out.append(s)
            for i in range(1, per_interval):
                s = self.step(k, s, solution.n, H=H, u0=k * self.H + (i - 1) * H)
                out.append(s)
        out.append(solution.nodes[-1])
        return out

    def undeformed_samples(self, nodes: list[ca.SX], per_interval: int = 4) -> list[ca.SX]:
        """The unloaded link at the same positions as samples() (states; [2:4] is the point)."""
        zero = ca.SX.zeros(2)
        out = []
        H = self.H / per_interval
        for k in range(self.K):
            s = nodes[k]
            out.append(s)
            for q in range(1, per_interval):
                s = self.step(k, s, zero, H=H, u0=k * self.H + (q - 1) * H, unloaded=True)
                out.append(s)
        out.append(nodes[-1])
        return out
