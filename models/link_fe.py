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

from models.link import LinkProperties


def _lagrange(nodes: np.ndarray, xi: float) -> tuple[np.ndarray, np.ndarray]:
    """Values and derivatives at xi of the Lagrange polynomials through `nodes`."""
    n = len(nodes)
    values, slopes = np.ones(n), np.zeros(n)
    for k in range(n):
        others = [nodes[j] for j in range(n) if j != k]
        denominator = np.prod([nodes[k] - o for o in others])
        values[k] = np.prod([xi - o for o in others]) / denominator
        slopes[k] = sum(np.prod([xi - o for i, o in enumerate(others) if i != m]) for m in range(len(others))) / denominator
    return values, slopes


@dataclass(frozen=True)
class ElementRule:
    """Numbers of one element (xi from 0 to 1): quadrature points and weights; the rotation's
    basis (values, slopes) at them; the strains' basis at them; and, per quadrature point q,
    the rule mapped onto [0, xi_q] (points' bases and weights) for the position there."""

    degree: int
    xi: np.ndarray
    weights: np.ndarray
    rotation: np.ndarray  # (q, degree + 1)
    slope: np.ndarray  # (q, degree + 1), d/dxi
    strain: np.ndarray  # (q, degree)
    partial_rotation: np.ndarray  # (q, q, degree + 1): basis at the points of [0, xi_q]
    partial_strain: np.ndarray  # (q, q, degree)
    partial_weights: np.ndarray  # (q, q): weights of [0, xi_q] (they sum to xi_q)


@lru_cache(maxsize=8)
def element_rule(degree: int) -> ElementRule:
    points = degree + 2
    gx, gw = np.polynomial.legendre.leggauss(points)
    xi, weights = (gx + 1) / 2, gw / 2
    nodes = np.linspace(0.0, 1.0, degree + 1)
    strain_nodes = (np.polynomial.legendre.leggauss(degree)[0] + 1) / 2

    def rotation_basis(at):
        return np.array([_lagrange(nodes, a)[0] for a in at]), np.array([_lagrange(nodes, a)[1] for a in at])

    def strain_basis(at):
        return np.array([_lagrange(strain_nodes, a)[0] for a in at])

    rotation, slope = rotation_basis(xi)
    partial_rotation = np.array([rotation_basis(xq * xi)[0] for xq in xi])
    partial_strain = np.array([strain_basis(xq * xi) for xq in xi])
    return ElementRule(degree, xi, weights, rotation, slope, strain_basis(xi), partial_rotation, partial_strain,
                       np.outer(xi, weights))


@dataclass
class QuadraturePoint:
    u: float
    weight: float  # of the whole link's rule (du)
    psi: ca.SX
    position: ca.SX  # (2,) centre line
    normal: ca.SX  # (2,) cross-section normal n(psi) (to the left of the tangent)


@dataclass
class LinkKinematics:
    """A discretized link's state: nodes (u, psi, position) at element ends, and quadrature
    points (where energy, weight and contact are evaluated)."""

    node_u: list[float]
    node_psi: list[ca.SX]
    node_position: list[ca.SX]
    points: list[QuadraturePoint]
    strain_energy: ca.SX


class LinkElements:
    """The discretization of one link: how many unknowns, and the kinematics and energy of
    given unknowns."""

    def __init__(self, props: LinkProperties, elements: int, degree: int):
        self.props, self.elements, self.degree = props, elements, degree
        self.rule = element_rule(degree)
        self.shear, self.axial = props.kGA is not None, props.EA is not None

    @property
    def n_rotations(self) -> int:
        return self.elements * self.degree + 1

    @property
    def n_strains(self) -> int:
        """Per strain field (shear, axial)."""
        return self.elements * self.degree

    def kinematics(self, theta: ca.SX, gamma: ca.SX | None, eps: ca.SX | None, start: ca.SX) -> LinkKinematics:
        """theta: nodal rotations (n_rotations), gamma/eps: strain coefficients (n_strains, or
        None), start: position of u = 0."""
        P, rule, p = self.props, self.rule, self.degree
        L, h = P.length, 1.0 / self.elements
        energy = ca.SX(0)
        position = start
        node_u, node_psi, node_position, points = [0.0], [P.eta(ca.SX(0)) + theta[0]], [start], []
        for e in range(self.elements):
            u0 = e * h
            th = theta[e * p:e * p + p + 1]
            g = gamma[e * p:e * p + p] if gamma is not None else None
            s = eps[e * p:e * p + p] if eps is not None else None

            def tangent(xi_point, basis_row, strain_row):
                u = ca.SX(u0 + h * xi_point)
                psi = P.eta(u) + ca.dot(ca.DM(basis_row), th)
                t, n = ca.vertcat(ca.cos(psi), ca.sin(psi)), ca.vertcat(-ca.sin(psi), ca.cos(psi))
                stretch = 1 + (ca.dot(ca.DM(strain_row), s) if s is not None else 0)
                shear = ca.dot(ca.DM(strain_row), g) if g is not None else 0
                return psi, n, L * (stretch * t + shear * n)

            increment = ca.SX.zeros(2)
            for q in range(len(rule.xi)):
                u = ca.SX(u0 + h * rule.xi[q])
                psi, n, r_u = tangent(rule.xi[q], rule.rotation[q], rule.strain[q])
                increment = increment + h * rule.weights[q] * r_u
                theta_u = ca.dot(ca.DM(rule.slope[q]), th) / h
                density = P.EI(u) * theta_u**2 / (2 * L)
                if g is not None:
                    density = density + L * P.kGA(u) * ca.dot(ca.DM(rule.strain[q]), g) ** 2 / 2
                if s is not None:
                    density = density + L * P.EA(u) * ca.dot(ca.DM(rule.strain[q]), s) ** 2 / 2
                energy = energy + h * rule.weights[q] * density
                partial = ca.SX.zeros(2)
                for k in range(len(rule.xi)):
                    partial = partial + h * rule.partial_weights[q, k] * tangent(
                        rule.xi[q] * rule.xi[k], rule.partial_rotation[q, k], rule.partial_strain[q, k])[2]
                points.append(QuadraturePoint(u0 + h * rule.xi[q], h * rule.weights[q], psi, position + partial, n))
            position = position + increment
            node_u.append(u0 + h)
            node_psi.append(P.eta(ca.SX(u0 + h)) + th[-1])
            node_position.append(position)
        return LinkKinematics(node_u, node_psi, node_position, points, energy)
