"""Where one element of a link (models.beams.link_fe) is evaluated, and the linear maps from there
to its integrals: the constants of the link element kernels (models.kernels.link_chain).

An element runs from xi = 0 to 1 (u = u0 + du xi). Its tangent
T(xi) = L [(1 + eps) t(psi) + gamma n(psi)] is evaluated at `points`; then

    Delta = du sum_s increment[s] T_s                 (the element's end less its start)
    P_q   = du sum_s mass_positions[q, s] T_s         (mass point q less the element's start)

with the mass points at the element's degree + 2 Gauss points (models.beams.link_fe lumps the
mass and rotary inertia there; the strain energy uses the same quadrature).

Two rules give these maps:
  "partial": the model of models.beams.link_fe exactly: Delta by the degree + 2 point Gauss rule,
      each P_q by that rule mapped onto [0, xi_q] (5 + 25 points for cubic elements);
  "interpolated": the tangent at `count` Gauss points, integrated exactly as the polynomial
      through them (Delta and every P_q from the same points: 8 for cubic elements). Its
      integrals differ from the partial rule's by the error of either rule, about
      (the element's turning)^10 / 10!: 1e-13 for 0.3 rad. Fewer points: 3.7 times less work.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from flexmech.models.beams.link_fe import element_rule

INTERPOLATED_POINTS = {1: 5, 2: 6, 3: 8, 4: 9, 5: 10, 6: 11}  # by degree: exact to 1e-12 at moderate turning


@dataclass(frozen=True)
class ElementPoints:
    degree: int
    name: str  # partial | interpolated
    xi: np.ndarray  # (ns,) where the tangent is evaluated
    rotation: np.ndarray  # (ns, degree + 1) the rotation's Lagrange basis there
    strain: np.ndarray  # (ns, degree) the strains' basis there
    increment: np.ndarray  # (ns,)
    mass_positions: np.ndarray  # (nq, ns)
    quad_xi: np.ndarray  # (nq,) mass points and strain quadrature
    quad_weights: np.ndarray  # (nq,) summing to 1
    quad_rotation: np.ndarray  # (nq, degree + 1)
    quad_slope: np.ndarray  # (nq, degree + 1) d/dxi of the rotation basis
    quad_strain: np.ndarray  # (nq, degree)

    @property
    def key(self) -> str:
        return f"{self.name}{len(self.xi)}"


@lru_cache(maxsize=16)
def element_points(degree: int, name: str = "interpolated") -> ElementPoints:
    rule = element_rule(degree)
    nq = len(rule.xi)
    if name == "partial":
        partial = rule.at_quadrature
        xi = np.concatenate([rule.xi, np.outer(rule.xi, rule.xi).ravel()])
        rotation = np.vstack([rule.rotation, partial.partial_rotation.reshape(-1, degree + 1)])
        strain = np.vstack([rule.strain, partial.partial_strain.reshape(-1, degree)])
        increment = np.concatenate([rule.weights, np.zeros(nq * nq)])
        positions = np.zeros((nq, nq + nq * nq))
        for q in range(nq):
            positions[q, nq + q * nq : nq + (q + 1) * nq] = partial.partial_weights[q]
    elif name == "interpolated":
        count = INTERPOLATED_POINTS[degree]
        gx, gw = np.polynomial.legendre.leggauss(count)
        xi, increment = (gx + 1) / 2, gw / 2
        rotation = _basis(np.linspace(0, 1, degree + 1), xi)
        strain = _basis((np.polynomial.legendre.leggauss(degree)[0] + 1) / 2, xi)
        positions = np.array([[_integral_of_lagrange(xi, s, rule.xi[q]) for s in range(count)] for q in range(nq)])
    else:
        raise ValueError(f"unknown element point rule '{name}' (partial, interpolated)")
    return ElementPoints(
        degree,
        name,
        xi,
        rotation,
        strain,
        increment,
        positions,
        rule.xi,
        rule.weights,
        rule.rotation,
        rule.slope,
        rule.strain,
    )


def _basis(nodes: np.ndarray, at: np.ndarray) -> np.ndarray:
    """(len(at), len(nodes)): the Lagrange polynomials through `nodes`, at `at`."""
    out = np.ones((len(at), len(nodes)))
    for k, node in enumerate(nodes):
        for j, other in enumerate(nodes):
            if j != k:
                out[:, k] *= (at - other) / (node - other)
    return out


def _integral_of_lagrange(nodes: np.ndarray, k: int, upper: float) -> float:
    """int_0^upper of the k-th Lagrange polynomial through `nodes`."""
    others = np.delete(nodes, k)
    coefficients = np.poly(others) / np.prod(nodes[k] - others)
    antiderivative = np.polyint(coefficients)
    return float(np.polyval(antiderivative, upper) - np.polyval(antiderivative, 0.0))
