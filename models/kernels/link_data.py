"""The data of a link's elements for the link element kernel (models.kernels.link_chain): per
element, what does not change in time (the initial angle eta at the rule's points, stiffnesses
and masses at the quadrature points, the element's length in u and its undeformed increment),
from the link's properties (models.elements.link) over the parameters."""

from __future__ import annotations

import casadi as ca
import numpy as np

from flexmech.models.documents.sections import section_properties
from flexmech.models.elements.link import LinkElementsTopology, link_properties
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.kernels.chain_signature import ChainSignature, data_layout


def signature_of(t: LinkElementsTopology, rule: str = "interpolated") -> ChainSignature:
    return ChainSignature(t.degree, t.shear, t.axial, rule)


def link_data(ctx: AssemblyContext, t: LinkElementsTopology, signature: ChainSignature) -> ca.SX:
    """(n_data, intervals): every element's data, over ctx.p."""
    props = link_properties(ctx, t)
    pts = signature.points
    du = 1.0 / t.intervals
    L = props.length
    zero = ca.SX(0)
    rotary_density = None
    if props.line_mass is not None:
        rho = ctx.P[f"/materials/{t.material}/density"]
        I = section_properties(ctx.P, t.section).I
        rotary_density = lambda u: L * rho * I(u)  # noqa: E731  rho I per unit u
    columns = []
    for e in range(t.intervals):
        u0 = e * du
        at_points = [ca.SX(u0 + du * float(xi)) for xi in pts.xi]
        at_quad = [ca.SX(u0 + du * float(xi)) for xi in pts.quad_xi]
        weights = [du * float(w) for w in pts.quad_weights]
        eta_points = [props.eta(u) for u in at_points]
        increment = du * sum(
            (float(w) * L * ca.vertcat(ca.cos(eta), ca.sin(eta)) for w, eta in zip(pts.increment, eta_points)),
            ca.SX.zeros(2),
        )
        parts = {
            "du": [ca.SX(du)],
            "length": [L],
            "eta_points": eta_points,
            "eta_quad": [props.eta(u) for u in at_quad],
            "EI": [props.EI(u) for u in at_quad],
            "kGA": [props.kGA(u) if props.kGA is not None else zero for u in at_quad],
            "EA": [props.EA(u) if props.EA is not None else zero for u in at_quad],
            "mass": [w * props.line_mass(u) if props.line_mass is not None else zero for w, u in zip(weights, at_quad)],
            "rotary": [w * rotary_density(u) if rotary_density is not None else zero for w, u in zip(weights, at_quad)],
            "undeformed_increment": [increment[0], increment[1]],
        }
        columns.append(ca.vertcat(*[value for name, _ in data_layout(signature) for value in parts[name]]))
    return ca.horzcat(*columns)


def undeformed_nodes(data: np.ndarray, signature: ChainSignature, start: np.ndarray) -> np.ndarray:
    """(2, intervals + 1): the undeformed nodes of a link from its start point and data."""
    layout = data_layout(signature)
    k = sum(size for name, size in layout if name != "undeformed_increment")
    increments = data[k : k + 2, :]
    return start[:, None] + np.concatenate([np.zeros((2, 1)), np.cumsum(increments, axis=1)], axis=1)
