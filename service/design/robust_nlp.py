"""The robust outputs' unknowns in the design NLP (service.design.nlp; the formulas:
service.design.robust).

Per load case and scatter that a robust objective or constraint names, a block S (n_z x sources)
of first-order state moves joins the unknowns, after the modes and the responses' amplitudes, with
K(z, p) S + R_p(z, p) L = 0 as equality rows (column by column). The block is linear in S and
shares K's sparsity, so it costs a sparse solve per IPOPT iteration, never a dense inverse in the
graph. Its start is the solve at the start's states, and an optimum's block is solved afresh at
the polished states (so its report is the first order of the state it reports)."""

from __future__ import annotations

import casadi as ca
import numpy as np

from flexmech.service.design.frequencies import unknown_bounds, vibration_start
from flexmech.service.design.robust import first_order_terms

# A block: (case, Robustness.scatter).
Block = tuple[int, tuple]


def sensitivity_blocks(refs) -> tuple[Block, ...]:
    """The (case, scatter) blocks the refs need, each once, in order of appearance."""
    return tuple(dict.fromkeys((ref.case, ref.robust.scatter) for ref in refs if ref.robust is not None))


def block_of(ref) -> Block:
    return ref.case, ref.robust.scatter


def block_size(structure, block: Block) -> int:
    return structure.n_unknowns * len(block[1][1][0])


def sensitivity_rows(structure, blocks: tuple[Block, ...], zs, ps) -> tuple[list, list, dict]:
    """The blocks' unknowns (vectors, column-major), their rows K S + R_p L, and per block the
    outputs and their moves (y, y_z S + y_p L) as graphs of the unknowns."""
    unknowns, rows, firsts = [], [], {}
    for j, block in enumerate(blocks):
        case, scatter = block
        n_sources = len(scatter[1][0])
        S = ca.SX.sym(f"S{j}", structure.n_unknowns, n_sources)
        y, K, R_pL, y_z, y_pL = first_order_terms(structure, scatter)(zs[case], ps[case])
        unknowns.append(ca.vec(S))
        rows.append(ca.vec(ca.mtimes(K, S) + R_pL))
        firsts[block] = (y, ca.mtimes(y_z, S) + y_pL)
    return unknowns, rows, firsts


def _solved(structure, blocks, zs, ps) -> np.ndarray:
    """The blocks' values S = -K^-1 R_p L at the states zs (column-major, concatenated)."""
    parts = []
    for case, scatter in blocks:
        _, K, R_pL, _, _ = (
            np.asarray(a, dtype=float) for a in first_order_terms(structure, scatter)(zs[case], ps[case])
        )
        try:
            S = -np.linalg.solve(K, R_pL)
        except np.linalg.LinAlgError:  # a singular start: let IPOPT find the block
            S = np.zeros_like(R_pL)
        parts.append(S.ravel(order="F"))
    return np.concatenate(parts) if parts else np.zeros(0)


def tail_start(problem, nlp, P: np.ndarray, zs, ps) -> np.ndarray:
    """The unknowns after the states at the start states zs: the modes, the responses'
    amplitudes (service.design.frequencies), then the sensitivity blocks."""
    structure = problem.mechanism.structure
    return np.concatenate([vibration_start(problem, nlp, P, zs, ps), _solved(structure, nlp.sensitivities, zs, ps)])


def tail_bounds(nlp) -> tuple[np.ndarray, np.ndarray]:
    """The bounds of the unknowns after the states (the sensitivity blocks free)."""
    lower, upper = unknown_bounds(nlp.frequencies, nlp.n_state, len(nlp.responses))
    n = nlp.n_sensitivity
    return np.concatenate([lower, np.full(n, -np.inf)]), np.concatenate([upper, np.full(n, np.inf)])


def polished_tail(problem, nlp, x: np.ndarray, zs, ps) -> np.ndarray:
    """x's unknowns after the states, the sensitivity blocks solved afresh at the states zs."""
    tail = np.asarray(x[nlp.n_states :], dtype=float)
    if not nlp.sensitivities:
        return tail
    n = nlp.n_sensitivity
    return np.concatenate([tail[: len(tail) - n], _solved(problem.mechanism.structure, nlp.sensitivities, zs, ps)])
