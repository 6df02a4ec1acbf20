"""The constant index arrays of one chain group (models.kernels.layout) for the kernel step
system (service.dynamics.kernel_system): where each element's and block's inputs come from
in Z and the affine parts, and where their outputs go, padded to whole chunks."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from flexmech.models.kernels.chunks import CHUNK

UNSET_AFFINE = 10_000  # offset past n_x marking a padded item's affine index (set once the angles are known)


def padded(n: int) -> int:
    return max(1, -(-n // CHUNK)) * CHUNK


@dataclass
class GroupIndex:
    """Constant index arrays of one chain group, padded to whole chunks."""

    elements: int  # padded
    blocks: int  # padded
    gather_u: list[int]  # (n_c x elements) flat, column-major, into [Z; 0]
    gather_affine: list[int]  # (n_c x elements) into [extended affine; 0]
    present: np.ndarray  # (1, elements)
    start: np.ndarray  # (1, elements): 1 at a chain's first element
    start_chain: list[int]  # per element: its chain among all chains (padding: 0)
    this: list[int]  # per block (reverse order): its element j's column in [packed | zero]
    prev: list[int]  # its element j-1's
    this_flags: np.ndarray  # (3, blocks): present, clamped start, last of the elements j
    prev_flags: np.ndarray  # (3, blocks): those of the elements j-1
    block_present: np.ndarray  # (1, blocks) reverse order
    flags: np.ndarray  # (2, blocks) reverse order: first, last
    end: list[int]  # (3 x blocks) flat into [Z; 0]: lambda_x, lambda_y, lambda_rot at a chain's last block
    forward: list[int]  # per block in order (padded): its reverse position
    chains: list[int]  # the chains' indices among all chains
    b0: list[int]  # per chain: the reverse position of its B_0
    last_element: list[int]  # per chain: its last element
    node_columns: list[int]  # per block in order: its node's column in [starts (chains), next (elements)]
    force_sum: np.ndarray  # (padded elements, padded blocks in order): F_j = lam_end + forces beyond j
    end_of_block: list[int]  # per block in order: lambda_x's index in [Z; 0] (padding: the zero)
    element_node: list[int]  # per element: its node e's block (in order)


def group_index(L, g, zero: int, prescribed_angle: Callable) -> GroupIndex:
    """The index arrays of chain group g of layout L; `zero` indexes the zero appended to Z,
    prescribed_angle(chain) a clamped start's prescribed angle among the extended affine's."""
    E, B = padded(g.n_elements), padded(g.n_blocks)
    gu, gaff, present, start, start_chain, eflags, chain_ids = _element_arrays(L, g, zero, prescribed_angle, E)
    blocks, this, prev, flags, end, forward, b0 = _block_arrays(L, g, zero, E, B)
    n_b = g.n_blocks
    pad = B - n_b
    block_present = np.array([[1.0] * n_b + [0.0] * pad])
    last_element = [c.first_block - ci + c.n_elements - 1 for ci, c in enumerate(g.chains)]
    n_chains, n_x = len(g.chains), L.n_x
    node_columns, force_sum, end_of_block = [], np.zeros((E, B)), []
    for k, (c, j, first) in enumerate(blocks):
        node_columns.append(g.chains.index(c) if j == 0 else n_chains + first + j - 1)
        force_sum[first + j : first + c.n_elements, k] = 1.0
        end_of_block.append(n_x + c.multiplier_offset)
    node_columns += [0] * pad
    end_of_block += [zero] * pad
    element_node = [c.first_block + e for c in g.chains for e in range(c.n_elements)]
    return GroupIndex(
        E,
        B,
        gu,
        gaff,
        np.array([present]),
        np.array([start]),
        start_chain,
        this,
        prev,
        eflags[:, this],
        eflags[:, prev],
        block_present,
        np.array(flags).T,
        end,
        forward,
        chain_ids,
        b0,
        last_element,
        node_columns,
        force_sum,
        end_of_block,
        element_node,
    )


def _element_arrays(L, g, zero: int, prescribed_angle: Callable, E: int):
    sig, n_x, n_el = g.signature, L.n_x, g.n_elements
    zero_affine = n_x + UNSET_AFFINE
    gu, gaff, present, start, start_chain, eflags = [], [], [], [], [], []
    chain_ids = [L.chains.index(c) for c in g.chains]
    for c, cid in zip(g.chains, chain_ids):
        for e in range(c.n_elements):
            for i in range(sig.n_c):
                x = c.coordinate_x(e, i)
                if x is None:  # a clamped start's theta_0: its start body's angle
                    angle = L.start_body_angle_x(c)
                    gu.append(angle if angle is not None else zero)
                    gaff.append(angle if angle is not None else n_x + prescribed_angle(c))
                else:
                    gu.append(x)
                    gaff.append(x)
            present.append(1.0)
            start.append(float(e == 0))
            start_chain.append(cid)
            eflags.append([1.0, float(e == 0 and c.topology.start == "clamped"), float(e == c.n_elements - 1)])
    for _ in range(E - n_el):
        gu += [zero] * sig.n_c
        gaff += [zero_affine] * sig.n_c
        present.append(0.0)
        start.append(0.0)
        start_chain.append(0)
    eflags += [[0.0, 0.0, 0.0]] * (E - n_el + 1)  # the padding, then the "no element" column
    eflags = np.array(eflags).T
    return gu, gaff, present, start, start_chain, eflags, chain_ids


def _block_arrays(L, g, zero: int, E: int, B: int):
    n_x, n_b = L.n_x, g.n_blocks
    blocks, e0 = [], 0  # (chain, j, its chain's first element) in order
    for c in g.chains:
        blocks += [(c, j, e0) for j in range(c.n_blocks)]
        e0 += c.n_elements
    none = E  # the zero column after the padded elements
    this, prev, flags, end = [], [], [], []
    for c, j, first in reversed(blocks):
        this.append(first + j if j < c.n_elements else none)
        prev.append(first + j - 1 if j > 0 else none)
        flags.append([float(j == 0), float(j == c.n_elements)])
        m = n_x + c.multiplier_offset
        if j == c.n_elements:
            end += [m, m + 1, m + 2 if c.topology.end == "clamped" else zero]
        else:
            end += [zero] * 3
    pad = B - n_b
    this += [none] * pad
    prev += [none] * pad
    flags += [[0.0, 0.0]] * pad
    end += [zero] * (3 * pad)
    forward = [n_b - 1 - k for k in range(n_b)] + list(range(n_b, B))
    b0 = [n_b - 1 - c.first_block for c in g.chains]
    return blocks, this, prev, flags, end, forward, b0
