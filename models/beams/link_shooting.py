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

from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import casadi as ca

from flexmech.models.beams.link_steps import general_step, local_form

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


class RightHandSide(NamedTuple):
    f: ca.Function  # (u, s, n, P) -> s'
    P: ca.SX  # the parameters f reads
    uniform: bool  # every coefficient uniform along the link: f computes no parameter alone


def rhs_function(props: LinkProperties, p: ca.SX, weighed: bool = True) -> RightHandSide:
    """f(u, s, n, P) -> s' for the state s (props.states) and the internal force n = (h, v) at
    u = 0; weighed (with gravity and a line mass), the force at u is n - mu(u) g: n less the
    weight of the part behind. P is the link's coefficients that are uniform along it (its
    length, and each stiffness, slope and line mass that does not vary with u), then p: they
    are computed once per link instead of at each of the hundreds of evaluations of f, and
    links of one kind share one form of f (models.beams.link_steps)."""
    u, s, n_start = ca.SX.sym("u"), ca.SX.sym("s", props.states), ca.SX.sym("n", 2)
    u_eta = ca.SX.sym("u_eta")
    fields = {
        "L": props.length,
        "EI": props.EI(u),
        "EA": props.EA(u) if props.EA is not None else None,
        "kGA": props.kGA(u) if props.kGA is not None else None,
        "slope": ca.substitute(ca.jacobian(ca.SX(props.eta(u_eta)), u_eta), u_eta, u),
        "mass": props.line_mass(u) if props.line_mass is not None else None,
    }
    given = {name: value for name, value in fields.items() if value is not None and not ca.SX(value).is_constant()}
    uniform = [name for name, value in given.items() if not ca.depends_on(value, u)]
    c = ca.SX.sym("c", len(uniform))
    at = {name: (c[uniform.index(name)] if name in uniform else value) for name, value in fields.items()}
    psi, m = s[0], s[1]
    n = n_start
    if weighed and props.line_mass is not None and props.gravity is not None:
        n = n_start - s[5] * props.gravity
    h, v = n[0], n[1]
    L, EI, EA, kGA = at["L"], at["EI"], at["EA"], at["kGA"]
    c_psi, s_psi = ca.cos(psi), ca.sin(psi)
    N = h * c_psi + v * s_psi
    V = -h * s_psi + v * c_psi
    eps = N / EA if EA is not None else 0
    gamma = V / kGA if kGA is not None else 0
    dx = L * ((1 + eps) * c_psi - gamma * s_psi)
    dy = L * ((1 + eps) * s_psi + gamma * c_psi)
    energy = m**2 / (2 * EI)
    if EA is not None:
        energy = energy + N**2 / (2 * EA)
    if kGA is not None:
        energy = energy + V**2 / (2 * kGA)
    ds = [at["slope"] + L * m / EI, h * dy - v * dx, dx, dy, L * energy]
    if at["mass"] is not None:
        ds.append(at["mass"])
    P = ca.vertcat(c, p)
    f = ca.Function("link_rhs", [u, s, n_start, P], [ca.vertcat(*ds)], ["u", "s", "n", "p"], ["ds"])
    return RightHandSide(f, ca.vertcat(*[fields[name] for name in uniform], p), len(uniform) == len(given))


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
    ds = ca.vertcat(
        slope - L * m / EI,
        L * (h * ca.sin(angle) - v * ca.cos(angle)),
        L * ca.cos(eta),
        L * ca.sin(eta),
        L * m**2 / (2 * EI),
    )
    return ca.Function("link_inverse_rhs", [u, s, n, ca.vertcat(p, q)], [ds], ["u", "s", "n", "p"], ["ds"])


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

    def __init__(
        self,
        props: LinkProperties,
        p: ca.SX,
        intervals: int,
        order: int,
        rhs: ca.Function | None = None,
        rhs_parameters: ca.SX | None = None,
    ):
        self.props = props
        self.K = intervals
        self.order = order
        f, P, self.uniform = rhs_function(props, p) if rhs is None else (rhs, rhs_parameters, False)
        self.weighed = rhs is None and props.line_mass is not None and props.gravity is not None
        # The unloaded link: no internal force and no weight (its own weight is a load).
        f_unloaded, P_unloaded, _ = rhs_function(props, p, weighed=False) if self.weighed else (f, P, None)
        self.H = 1.0 / intervals
        loaded = local_form(f)
        self._forms = {False: loaded, True: loaded if f_unloaded is f else local_form(f_unloaded)}
        self._q = {False: P[loaded.used], True: P_unloaded[self._forms[True].used]}

    def step(self, k: int, s, n, H=None, u0=None, order=None, unloaded: bool = False, inline: bool = True):
        """s at u0 + H (default: node k to node k + 1), by the general step of the link's form
        of right-hand side (models.beams.link_steps). inline=False keeps the step a call in the
        graph: for what only reports (samples, error estimates), which then costs a node to
        build instead of the step's whole expression, and is differentiated and generated as a
        call."""
        H = self.H if H is None else H
        u0 = k * self.H if u0 is None else u0
        step = general_step(self._forms[unloaded], order or self.order)
        args = [ca.SX(u0), s, n, self._q[unloaded], ca.SX(H)]
        return step(*args) if inline else step.call(args, False, True)[0]

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
        # Unloaded, each step recomputes what depends on the parameters alone (a straight
        # link's cos and sin of its angle, at every evaluation): merged here, on the link's
        # few thousand nodes, the structure's residual needs no pass over it all.
        return ca.vertsplit(ca.cse(ca.vertcat(*nodes)), s.numel())

    def solve_nodes(self, zl: ca.SX, start_xy: ca.SX, undeformed: list[ca.SX]) -> LinkSolution:
        """Deformed node states from the link's unknowns zl = [h, v, dpsi0, m0, (dpsi, m, dx,
        dy) at nodes 1..K-1] (deviations from `undeformed`), the start at `start_xy`."""
        n = zl[0:2]
        nodes = [
            self._with_energy_reset(
                ca.vertcat(undeformed[0][0] + zl[2], zl[3], start_xy[0], start_xy[1]), undeformed[0]
            )
        ]
        for k in range(1, self.K):
            block = zl[4 * k : 4 * k + 4]
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
            full = self.step(k, s, solution.n, inline=False)
            half = self.step(k, s, solution.n, H=self.H / 2, inline=False)
            half = self.step(k, half, solution.n, H=self.H / 2, u0=(k + 0.5) * self.H, inline=False)
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
                s = self.step(k, s, solution.n, H=H, u0=k * self.H + (i - 1) * H, inline=False)
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
                s = self.step(k, s, zero, H=H, u0=k * self.H + (q - 1) * H, unloaded=True, inline=False)
                out.append(s)
        out.append(nodes[-1])
        return out
