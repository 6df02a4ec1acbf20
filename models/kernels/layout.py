"""Where every unknown of a structure's kernel system lives.

State (between steps): the energy form's coordinates x (free body coordinates, then every
element's own variables, in document order: models.graph.forms) with their rates and
accelerations, the energy form's multipliers lam (every element's equalities, in document
order), and per node of every link discretized by elements its position, velocity,
acceleration and internal force (`aux`, 8 per node: models.kernels.link_chain).

Newton unknowns of a step: per chain group (the links of one ChainSignature, their chains
one after another) its blocks (models.kernels.chain_solver), then the global unknowns: the
coordinates that are not in a chain (free body coordinates, other elements' own variables)
and every multiplier. Computed from the topology alone: no graph is built here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import numpy as np

from flexmech.models.elements import FAMILIES
from flexmech.models.elements.link import LinkElementsTopology
from flexmech.models.graph.structure import Structure
from flexmech.models.kernels.chain_signature import NODE, ChainSignature
from flexmech.models.kernels.chain_solver import BORDER, BlockLayout
from flexmech.models.kernels.link_data import signature_of


def own_counts(t) -> tuple[int, int]:
    """(own variables, equalities) of an element in the energy form, as its family counts them
    (joints: multipliers only; springs, flexures: none)."""
    counts = getattr(FAMILIES.of(t), "energy_form_counts", None)
    return counts(t) if counts is not None else (0, t.unknowns)


def runs_in_chains(t) -> bool:
    """Whether the element runs as a chain of element kernels (its family says)."""
    return getattr(FAMILIES.of(t), "kernel_chain", False)


@dataclass
class Chain:
    """A link discretized by elements, as a chain of blocks."""

    element: int  # index in structure.elements
    topology: LinkElementsTopology
    x_offset: int  # where its own variables start in x
    multiplier_offset: int  # where its end multipliers start in lam
    first_block: int  # in its group
    aux_offset: int  # where its nodes' quantities start in aux
    signature: ChainSignature

    @property
    def n_elements(self) -> int:
        return self.topology.intervals

    @property
    def n_blocks(self) -> int:
        return self.n_elements + 1

    def coordinate_x(self, e: int, i: int) -> int | None:
        """x index of element e's i-th coordinate (None: a clamped start's theta_0, the start
        body's angle)."""
        t, p = self.topology, self.topology.degree
        n_rot = t.intervals * p + (1 if t.start == "pinned" else 0)
        first = 0 if t.start == "pinned" else 1
        if i <= p:
            node = e * p + i
            return None if node < first else self.x_offset + node - first
        j = i - p - 1
        strains = t.intervals * p
        kind, k = divmod(j, p)  # 0: the first strain field present, 1: the second
        return self.x_offset + n_rot + kind * strains + e * p + k


@dataclass
class ChainGroup:
    signature: ChainSignature
    chains: list[Chain] = field(default_factory=list)

    @property
    def blocks(self) -> BlockLayout:
        return BlockLayout(self.signature)

    @property
    def n_blocks(self) -> int:
        return sum(c.n_blocks for c in self.chains)

    @property
    def n_elements(self) -> int:
        return sum(c.n_elements for c in self.chains)


class KernelLayout:
    def __init__(self, structure: Structure, rule: str = "interpolated"):
        self.structure, self.rule = structure, rule
        n_free = len(structure.free)
        x_names = [structure.coordinate_name(b, c) for b, c in structure.free]
        lam_names: list[str] = []
        x_global = list(range(n_free))  # x indices that are global unknowns
        groups: dict[ChainSignature, ChainGroup] = {}
        self.chains: list[Chain] = []
        self.other_elements: list[tuple[int, int, int, int]] = []  # (element, x offset, own, lam offset)
        aux = 0
        for k, t in enumerate(structure.elements):
            own, eq = own_counts(t)
            names = [f"{t.name}.{name}" for name, _ in FAMILIES.of(t).unknowns(t)]
            if runs_in_chains(t):
                sig = signature_of(t, rule)
                group = groups.setdefault(sig, ChainGroup(sig))
                chain = Chain(k, t, len(x_names), len(lam_names), group.n_blocks, aux, sig)
                group.chains.append(chain)
                self.chains.append(chain)
                aux += chain.n_blocks * NODE
            else:
                self.other_elements.append((k, len(x_names), own, len(lam_names)))
                x_global += list(range(len(x_names), len(x_names) + own))
            x_names += names[:own]
            lam_names += names[own : own + eq]
        self.groups = list(groups.values())
        self.x_names, self.lam_names = tuple(x_names), tuple(lam_names)
        self.x_global = tuple(x_global)
        self.n_aux = aux

    @property
    def n_x(self) -> int:
        return len(self.x_names)

    @property
    def n_lam(self) -> int:
        return len(self.lam_names)

    @property
    def n_global(self) -> int:
        """Global Newton unknowns: the coordinates outside chains, then every multiplier."""
        return len(self.x_global) + self.n_lam

    @cached_property
    def group_offsets(self) -> list[int]:
        """Where each group's blocks start in the Newton unknowns."""
        offsets, k = [], 0
        for g in self.groups:
            offsets.append(k)
            k += g.n_blocks * g.blocks.size
        return offsets

    @property
    def n_block_unknowns(self) -> int:
        return sum(g.n_blocks * g.blocks.size for g in self.groups)

    @property
    def n_unknowns(self) -> int:
        return self.n_block_unknowns + self.n_global

    def global_index_of_x(self, i: int) -> int:
        """Newton unknown index of global coordinate x[i]."""
        return self.n_block_unknowns + self.x_global.index(i)

    def lam_index(self, j: int) -> int:
        return self.n_block_unknowns + len(self.x_global) + j

    @cached_property
    def x_unknown(self) -> np.ndarray:
        """(n_x,) Newton unknown index of every coordinate."""
        out = np.full(self.n_x, -1, dtype=int)
        for k, i in enumerate(self.x_global):
            out[i] = self.n_block_unknowns + k
        for g, offset in zip(self.groups, self.group_offsets):
            size, bl = g.blocks.size, g.blocks
            for c in g.chains:
                for e in range(c.n_elements):
                    for i, (which, slot) in enumerate(bl.unknown_slots[: g.signature.n_c]):
                        x = c.coordinate_x(e, i)
                        if x is not None:
                            out[x] = offset + (c.first_block + e + which) * size + slot
        assert (out >= 0).all(), "every coordinate has a Newton unknown"
        return out

    def start_body_angle_x(self, chain: Chain) -> int | None:
        """x index of a chain's start body's angle (None: prescribed)."""
        b = chain.topology.start_body
        return self.structure.free.index((b, 2)) if (b, 2) in self.structure.free else None

    def border_columns(self, chain: Chain) -> list[int]:
        """Newton unknown index of the chain's BORDER columns (-1: none)."""
        s, out = self.structure, []
        b = chain.topology.start_body
        for c in range(3):
            out.append(self.global_index_of_x(s.free.index((b, c))) if (b, c) in s.free else -1)
        n_end = 3 if chain.topology.end == "clamped" else 2
        out += [self.lam_index(chain.multiplier_offset + j) if j < n_end else -1 for j in range(3)]
        return out

    def border_rows(self, chain: Chain) -> list[int]:
        """The chain's BORDER rows as indices into the global part's rows (all body coordinates,
        3 per body, then every multiplier's equation): never -1."""
        b, n_bodies = chain.topology.start_body, len(self.structure.bodies)
        n_end = 3 if chain.topology.end == "clamped" else 2
        ends = [3 * n_bodies + chain.multiplier_offset + j if j < n_end else -1 for j in range(3)]
        return [3 * b, 3 * b + 1, 3 * b + 2] + ends


__all__ = ["BORDER", "Chain", "ChainGroup", "KernelLayout", "own_counts"]


@lru_cache(maxsize=32)
def layout_of(structure: Structure, rule: str = "interpolated") -> KernelLayout:
    """The structure's layout, kept: a run and its engine share one."""
    return KernelLayout(structure, rule)
