"""The forward sweep of a chain (models.kernels.link_chain): one element's kernel with its
start node carried from the element before, so that the node kinematics of a whole chain come
from one pass of mapaccum and the backward elimination (models.kernels.chain_solver) needs
only each element's packed rows."""

from __future__ import annotations

import casadi as ca

from flexmech.models.kernels.chain_signature import NODE, ChainSignature
from flexmech.models.kernels.link_chain import ElementEquations, ElementSymbols, element_symbols

SWEEP_INPUTS = ["node", "u", "affine", "k", "damping", "gravity", "data", "start", "start_node"]
SWEEP_OUTPUTS = ["next", "packed", "energies"]


def packed_size(signature: ChainSignature) -> int:
    """An element's sweep output for the backward sweep: gen rows (n_c), force (2), lever (2 n_c)."""
    return 3 * signature.n_c + 2


def sweep_function(signature: ChainSignature) -> ca.Function:
    """One element in the forward sweep along a chain: (node (rho, v, a of node e: the carry),
    u, affine, k, damping, gravity, data, start, start_node) -> (next (node e+1's rho, v, a),
    packed = [gen (its coordinates' rows without its end force); force (f: F_e = F_{e+1} + f);
    vec(lever) (dDelta/dc: the end force's share of the rows is lever^T F_{e+1})], energies).
    At a chain's first element (start = 1) the node is start_node, from the start body."""
    sym = element_symbols(signature)
    carry, start, start_node = ca.SX.sym("node", 6), ca.SX.sym("start"), ca.SX.sym("start_node", 6)
    node = (1 - start) * carry + start * start_node
    n_c = signature.n_c
    aux = ca.vertcat(node[0:2], node[2:4], node[4:6], ca.SX.zeros(2), ca.SX.zeros(NODE))
    u = ca.vertcat(sym.u[:n_c], aux)
    eq = ElementEquations(signature, ElementSymbols(u, sym.affine, sym.k, sym.damping, sym.gravity, sym.data))
    inputs = [carry, sym.u[:n_c], sym.affine, sym.k, sym.damping, sym.gravity, sym.data, start, start_node]
    outputs = [node + eq.increments, ca.vertcat(eq.gen_inner, eq.force, ca.vec(eq.lever)), eq.energies]
    return ca.Function(f"{signature.key}_sweep", inputs, outputs, SWEEP_INPUTS, SWEEP_OUTPUTS, {"cse": True})
