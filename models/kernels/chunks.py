"""The units of compiled code: each kernel of a chain signature (models.kernels.link_chain,
models.kernels.chain_solver) run over CHUNK items (elements or blocks) in one call.

Calling a kernel once per element from CasADi's virtual machine costs about as much as the
kernel's own arithmetic; a chunk costs one call for CHUNK items. Each item is gated: a
Switch between the kernel and a pass-through that keeps the carry and writes zeros, on the
item's `go` flag: padding (a structure's last chunk is filled up with absent items) and
converged Newton iterations (every item's go is 0) cost a branch in compiled code, not the
kernel. CHUNK is a constant: the chunks of a signature are compiled once and serve every
structure, whatever its number of elements.

Chunk inputs are the kernel's, each a matrix of CHUNK columns (the carry: one column), with
`go` (1 x CHUNK) first; outputs likewise, the carry after the last item first.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca

from flexmech.models.kernels.chain_signature import ChainSignature
from flexmech.models.kernels.chain_solver import solver_functions
from flexmech.models.kernels.chain_sweep import sweep_function
from flexmech.models.kernels.link_chain import jacobian_function

CHUNK = 8


def _pass_through(kernel: ca.Function, carried: bool) -> ca.Function:
    """The kernel's signature, doing nothing: the carry (input and output 0) kept, zeros out."""
    inputs = [ca.SX.sym(kernel.name_in(i), kernel.sparsity_in(i)) for i in range(kernel.n_in())]
    outputs = []
    for o in range(kernel.n_out()):
        if carried and o == 0:
            outputs.append(inputs[0])
        else:
            outputs.append(ca.SX.zeros(kernel.sparsity_out(o)))
    return ca.Function(f"{kernel.name()}_idle", inputs, outputs, kernel.name_in(), kernel.name_out())


def chunk_of(kernel: ca.Function, carried: bool, size: int = CHUNK) -> ca.Function:
    """(go (1 x size), inputs...) -> outputs: the kernel over `size` items, each run only
    where go is 1. carried: input 0 is a carry from item to item, and the outputs are the
    carry after the last item, then the kernel's outputs per item (its carry after each)."""
    gated = ca.Function.if_else(f"{kernel.name()}_gated", kernel, _pass_through(kernel, carried))
    name = f"{kernel.name()}_chunk"
    if not carried:
        return gated.map(name, "serial", size, [], [])
    steps = gated.mapaccum(f"{kernel.name()}_steps", size, [1], [0])
    inputs = [ca.MX.sym(f"i{i}", steps.sparsity_in(i)) for i in range(steps.n_in())]
    outputs = steps(*inputs)
    return ca.Function(
        name, inputs, [outputs[0][:, -1], *outputs], ["go", *kernel.name_in()], ["last", *kernel.name_out()]
    )


@dataclass(frozen=True)
class Chunks:
    """The chunk Functions of one chain signature, and how many numbers a block keeps."""

    sweep: ca.Function
    jacobian: ca.Function
    factor: ca.Function
    backward: ca.Function
    substitute: ca.Function
    factor_size: int

    def functions(self) -> dict[str, ca.Function]:
        return {
            "sweep": self.sweep,
            "jacobian": self.jacobian,
            "factor": self.factor,
            "backward": self.backward,
            "substitute": self.substitute,
        }


@lru_cache(maxsize=16)
def chunks(signature: ChainSignature) -> Chunks:
    solver = solver_functions(signature)
    return Chunks(
        chunk_of(sweep_function(signature), True),
        chunk_of(jacobian_function(signature), False),
        chunk_of(solver.factor, True),
        chunk_of(solver.backward, True),
        chunk_of(solver.substitute, True),
        solver.factor_size,
    )
