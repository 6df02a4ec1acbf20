"""A displacement-based discretization of a link (seed 002's elastica, Reissner's beam with
shear and axial strain), for energy minimization and contact.

The link (u from 0 to 1, length L, initial tangent angle eta(u)) is cut into `elements` equal
elements. On each, the rotation theta(u) = psi(u) - eta(u) is a Lagrange polynomial of
`degree` through equally spaced nodes (continuous between elements); the shear strain gamma
and the axial strain eps, when the link has them, are polynomials of degree - 1 per element
(discontinuous: they are local to a section). The centre line follows from its tangent,

    r(u) = r(0) + L int_0^u [(1 + eps) t(psi) + gamma n(psi)] du',   t = (cos, sin), n = (-sin, cos),

integrated by Gauss-Legendre quadrature of degree + 2 points per element, and the strain
energy is

    U = int_0^1 [EI theta_u^2 / (2 L) + L (kGA gamma^2 + EA eps^2) / 2] du

by the same rule. Positions at the quadrature points (where contact is checked) are
integrated from their element's start by the rule mapped onto the part before them. The
error of positions and energy falls as h^(2 degree) for smooth solutions (tests assert it).

Every quantity is a CasADi expression of the nodal rotations (deviations from the unloaded
link, so zero is the undeformed state) and the strains.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from flexmech.models.beams.link_shooting import LinkProperties


def _lagrange(nodes: np.ndarray, xi: float) -> tuple[np.ndarray, np.ndarray]:
    """Values and derivatives at xi of the Lagrange polynomials through `nodes`."""
    n = len(nodes)
    values, slopes = np.ones(n), np.zeros(n)
    for k in range(n):
        others = [nodes[j] for j in range(n) if j != k]
        denominator = np.prod([nodes[k] - o for o in others])
        values[k] = np.prod([xi - o for o in others]) / denominator
        slopes[k] = (
            sum(np.prod([xi - o for i, o in enumerate(others) if i != m]) for m in range(len(others))) / denominator
        )
    return values, slopes


@dataclass(frozen=True)
class PartialRule:
    """Positions at points xi_j of an element: the element's quadrature mapped onto [0, xi_j]
    (the rotation's and strains' bases at its points, and its weights, summing to xi_j)."""

    xi: np.ndarray  # (m,)
    rotation: np.ndarray  # (m, degree + 1): the rotation's basis at xi_j
    strain: np.ndarray  # (m, degree): the strains' basis at xi_j
    quadrature_xi: np.ndarray  # (q,): the element's quadrature points (mapped by xi_j)
    partial_rotation: np.ndarray  # (m, q, degree + 1)
    partial_strain: np.ndarray  # (m, q, degree)
    partial_weights: np.ndarray  # (m, q)


@dataclass(frozen=True)
class ElementRule:
    """Numbers of one element (xi from 0 to 1): the quadrature (degree + 2 Gauss points) and
    the bases at its points; where positions are needed: at the quadrature points (a link's
    weight) and at the contact points (the degree-point Gauss rule: as many per element as it
    has rotations, so a wrapped part keeps its constraints independent)."""

    degree: int
    xi: np.ndarray
    weights: np.ndarray
    rotation: np.ndarray  # (q, degree + 1)
    slope: np.ndarray  # (q, degree + 1), d/dxi
    strain: np.ndarray  # (q, degree)
    at_quadrature: PartialRule
    at_contact: PartialRule
    contact_weights: np.ndarray  # (degree,) of the degree-point rule


@lru_cache(maxsize=8)
def element_rule(degree: int) -> ElementRule:
    gx, gw = np.polynomial.legendre.leggauss(degree + 2)
    xi, weights = (gx + 1) / 2, gw / 2
    nodes = np.linspace(0.0, 1.0, degree + 1)
    cx, cw = np.polynomial.legendre.leggauss(degree)
    strain_nodes, contact_weights = (cx + 1) / 2, cw / 2

    def rotation_basis(at):
        return np.array([_lagrange(nodes, a)[0] for a in at]), np.array([_lagrange(nodes, a)[1] for a in at])

    def strain_basis(at):
        return np.array([_lagrange(strain_nodes, a)[0] for a in at])

    def partial(at: np.ndarray) -> PartialRule:
        return PartialRule(
            at,
            rotation_basis(at)[0],
            strain_basis(at),
            xi,
            np.array([rotation_basis(a * xi)[0] for a in at]),
            np.array([strain_basis(a * xi) for a in at]),
            np.outer(at, weights),
        )

    rotation, slope = rotation_basis(xi)
    return ElementRule(
        degree, xi, weights, rotation, slope, strain_basis(xi), partial(xi), partial(strain_nodes), contact_weights
    )


@dataclass
class LinkPoint:
    u: float
    weight: float  # of the whole link's rule (du) the point belongs to
    psi: ca.SX
    position: ca.SX | None  # (2,) centre line (None where not needed)
    normal: ca.SX  # (2,) cross-section normal n(psi) (to the left of the tangent)


@dataclass
class LinkKinematics:
    """A discretized link's state: nodes (u, psi, position) at element ends, quadrature
    points (energy; positions when the link weighs) and contact points."""

    node_u: list[float]
    node_psi: list[ca.SX]
    node_position: list[ca.SX]
    points: list[LinkPoint]
    contact_points: list[LinkPoint]
    strain_energy: ca.SX
    elongation: ca.SX  # the centre line's length less the link's: the integral of the axial strain


class LinkElements:
    """The discretization of one link: how many unknowns, and the kinematics and energy of
    given unknowns."""

    def __init__(self, props: LinkProperties, elements: int, degree: int):
        self.props, self.elements, self.degree = props, elements, degree
        self.rule = element_rule(degree)
        self._steps: dict[tuple, _ElementStep] = {}

    @property
    def n_rotations(self) -> int:
        return self.elements * self.degree + 1

    @property
    def n_strains(self) -> int:
        """Per strain field (shear, axial)."""
        return self.elements * self.degree

    def kinematics(
        self, theta: ca.SX, gamma: ca.SX | None, eps: ca.SX | None, start: ca.SX, positions_at_quadrature: bool = False
    ) -> LinkKinematics:
        """theta: nodal rotations (n_rotations), gamma/eps: strain coefficients (n_strains, or
        None), start: position of u = 0."""
        P, rule, p = self.props, self.rule, self.degree
        h = 1.0 / self.elements
        step = self._element_step(gamma is not None, eps is not None, positions_at_quadrature)
        energy, elongation = ca.SX(0), ca.SX(0)
        position = start
        node_u, node_psi, node_position, points, contact = [0.0], [P.eta(ca.SX(0)) + theta[0]], [start], [], []
        for e in range(self.elements):
            local = [theta[e * p : e * p + p + 1]]
            local += [field[e * p : e * p + p] for field in (gamma, eps) if field is not None]
            at_end, energy, elongation, psi, normal, where, contact_psi, contact_normal, contact_where = step(
                *local, position, energy, elongation, e * h
            )
            for q in range(len(rule.xi)):
                points.append(
                    LinkPoint(
                        e * h + h * rule.xi[q],
                        h * rule.weights[q],
                        psi[q],
                        where[:, q] if positions_at_quadrature else None,
                        normal[:, q],
                    )
                )
            for j in range(len(rule.at_contact.xi)):
                contact.append(
                    LinkPoint(
                        e * h + h * rule.at_contact.xi[j],
                        h * rule.contact_weights[j],
                        contact_psi[j],
                        contact_where[:, j],
                        contact_normal[:, j],
                    )
                )
            position = at_end
            node_u.append(e * h + h)
            node_psi.append(P.eta(ca.SX(e * h + h)) + theta[e * p + p])
            node_position.append(position)
        return LinkKinematics(node_u, node_psi, node_position, points, contact, energy, elongation)

    def _element_step(self, shear: bool, axial: bool, positions_at_quadrature: bool) -> _ElementStep:
        """One element's kinematics as a Function, built once and called (inlined) on every
        element: the same expressions as writing them out element by element, built in a
        fraction of the time (a link's graph is mostly this)."""
        key = (shear, axial, positions_at_quadrature)
        if key not in self._steps:
            self._steps[key] = _element_step(self.props, self.rule, 1.0 / self.elements, *key)
        return self._steps[key]


@dataclass(frozen=True)
class _ElementStep:
    """(theta_e, [gamma_e], [eps_e], start, energy, elongation, u0) -> (end position, energy,
    elongation, psi (q), normals (2 x q), positions (2 x q; zeros unless asked), contact psi
    (c), contact normals (2 x c), contact positions (2 x c)): one element from u0, the energy
    and elongation carried on (summed in the order of writing them out element by element)."""

    function: ca.Function
    free: list  # the symbols of the properties' expressions (parameters), passed through

    def __call__(self, *args):
        return self.function(*args, *self.free)


def _element_step(
    props: LinkProperties, rule: ElementRule, h: float, shear: bool, axial: bool, positions_at_quadrature: bool
) -> _ElementStep:
    p = rule.degree
    theta = ca.SX.sym("theta", p + 1)
    gamma = ca.SX.sym("gamma", p) if shear else None
    eps = ca.SX.sym("eps", p) if axial else None
    start, energy_in, elongation_in, u0 = (
        ca.SX.sym("start", 2),
        ca.SX.sym("energy"),
        ca.SX.sym("elongation"),
        ca.SX.sym("u0"),
    )
    element = _Element(props, u0, h, theta, gamma, eps)
    energy, elongation = energy_in, elongation_in
    increment = ca.SX.zeros(2)
    psis, normals, wheres = [], [], []
    for q in range(len(rule.xi)):
        psi, normal, r_u = element.tangent(rule.xi[q], rule.rotation[q], rule.strain[q])
        increment = increment + h * rule.weights[q] * r_u
        energy = energy + h * rule.weights[q] * element.energy_density(rule.xi[q], rule.slope[q], rule.strain[q])
        if eps is not None:
            elongation = elongation + h * rule.weights[q] * props.length * element.axial_strain(rule.strain[q])
        psis.append(psi)
        normals.append(normal)
        wheres.append(element.position(start, rule.at_quadrature, q) if positions_at_quadrature else ca.SX.zeros(2))
    contact_psi, contact_normals, contact_wheres = [], [], []
    for j in range(len(rule.at_contact.xi)):
        psi, normal, _ = element.tangent(rule.at_contact.xi[j], rule.at_contact.rotation[j], rule.at_contact.strain[j])
        contact_psi.append(psi)
        contact_normals.append(normal)
        contact_wheres.append(element.position(start, rule.at_contact, j))
    outputs = [
        start + increment,
        energy,
        elongation,
        ca.vertcat(*psis),
        ca.horzcat(*normals),
        ca.horzcat(*wheres),
        ca.vertcat(*contact_psi),
        ca.horzcat(*contact_normals),
        ca.horzcat(*contact_wheres),
    ]
    inputs = [theta] + [field for field in (gamma, eps) if field is not None] + [start, energy_in, elongation_in, u0]
    declared = {v.element_hash() for symbol in inputs for v in ca.symvar(symbol)}
    free = [v for v in ca.symvar(ca.vertcat(*[ca.vec(o) for o in outputs])) if v.element_hash() not in declared]
    return _ElementStep(ca.Function("link_element_step", [*inputs, *free], outputs), free)


class _Element:
    """One element's fields: rotation, strains, tangent, energy density, positions inside."""

    def __init__(self, props: LinkProperties, u0: float, h: float, theta, gamma, eps):
        self.props, self.u0, self.h, self.theta, self.gamma, self.eps = props, u0, h, theta, gamma, eps

    def tangent(self, xi: float, rotation_row, strain_row):
        """(psi, n(psi), dr/du) at xi."""
        P = self.props
        psi = P.eta(ca.SX(self.u0 + self.h * xi)) + ca.dot(ca.DM(rotation_row), self.theta)
        t, n = ca.vertcat(ca.cos(psi), ca.sin(psi)), ca.vertcat(-ca.sin(psi), ca.cos(psi))
        stretch = 1 + (ca.dot(ca.DM(strain_row), self.eps) if self.eps is not None else 0)
        shear = ca.dot(ca.DM(strain_row), self.gamma) if self.gamma is not None else 0
        return psi, n, P.length * (stretch * t + shear * n)

    def axial_strain(self, strain_row) -> ca.SX:
        return ca.dot(ca.DM(strain_row), self.eps)

    def energy_density(self, xi: float, slope_row, strain_row) -> ca.SX:
        P, L = self.props, self.props.length
        u = ca.SX(self.u0 + self.h * xi)
        theta_u = ca.dot(ca.DM(slope_row), self.theta) / self.h
        density = P.EI(u) * theta_u**2 / (2 * L)
        if self.gamma is not None:
            density = density + L * P.kGA(u) * ca.dot(ca.DM(strain_row), self.gamma) ** 2 / 2
        if self.eps is not None:
            density = density + L * P.EA(u) * ca.dot(ca.DM(strain_row), self.eps) ** 2 / 2
        return density

    def position(self, start: ca.SX, partial: PartialRule, j: int) -> ca.SX:
        """The centre line at the partial rule's j-th point, from the element's start."""
        out = start
        for k in range(partial.partial_weights.shape[1]):
            xi = partial.xi[j] * partial.quadrature_xi[k]
            out = (
                out
                + self.h
                * partial.partial_weights[j, k]
                * self.tangent(xi, partial.partial_rotation[j, k], partial.partial_strain[j, k])[2]
            )
        return out
