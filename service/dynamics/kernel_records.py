"""The records that the kernel system (service.dynamics.kernel_system) passes between its
pieces: a step's shared inputs, the residual eliminated along the chains and the factors of the
Newton system. Plain records, kept apart from the system that fills them; the time step's
Functions (service.dynamics.kernel_window) pack them into their inputs and outputs (parts, of)."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca


@dataclass
class Evaluation:
    """The residual at Z, eliminated along the chains, and what comes with it."""

    y: list[ca.MX]  # per group (block size x padded blocks, reverse order): the eliminated blocks
    rhs: ca.MX  # the global rows' right-hand side, condensed (n_global)
    all_rows: ca.MX  # rows of every body coordinate (prescribed too), own variable and multiplier
    routed: ca.MX  # (clamped chains,): each clamped start's theta_0 row (its start body's angle row)
    energies: ca.MX  # (6,): the links' kinetic and strain energy, first moment and momentum of their mass
    global_energies: ca.MX  # (6,): the global part's (models.kernels.global_part.ENERGIES)
    norm: ca.MX

    def parts(self) -> list[ca.MX]:
        return [*self.y, self.rhs, self.all_rows, self.routed, self.energies, self.global_energies, self.norm]

    @classmethod
    def of(cls, parts: list, groups: int) -> Evaluation:
        return cls(list(parts[:groups]), *parts[groups : groups + 6])


@dataclass
class Factors:
    kept_reverse: list[ca.MX]  # per group (factor size x padded blocks), blocks in reverse order
    kept_forward: list[ca.MX]  # per group, in order (substitution)
    inverse: ca.MX  # of the condensed global system

    def parts(self) -> list[ca.MX]:
        return [*self.kept_reverse, *self.kept_forward, self.inverse]

    @classmethod
    def of(cls, parts: list, groups: int) -> Factors:
        return cls(list(parts[:groups]), list(parts[groups : 2 * groups]), parts[2 * groups])


@dataclass
class StepInputs:
    """What a step's iterations share (everything that does not depend on Z)."""

    affine: tuple  # (cX, cV, cA) of every coordinate
    k: ca.MX  # (kx, kv, ka, k_rho)
    p: ca.MX
    pdot: ca.MX
    pddot: ca.MX
    damping: ca.MX
    mask: ca.MX
    element_affine: list  # per group (3 n_c x padded elements)
    element_constants: list  # per group: (k, damping, gravity rows)
    data: list  # per group (n_data x padded elements)
    affine_global: ca.MX  # (global coordinates x 3)

    def parts(self) -> list[ca.MX]:
        constants = [c for group in self.element_constants for c in group]
        scalars = [self.k, self.p, self.pdot, self.pddot, self.damping, self.mask]
        return [*self.affine, *scalars, *self.element_affine, *constants, *self.data, self.affine_global]

    def symbols(self) -> StepInputs:
        """Symbols of the same shapes: the inputs of a Function that takes a step's inputs made once."""
        fresh = iter([ca.MX.sym(f"step_input{i}", part.sparsity()) for i, part in enumerate(self.parts())])
        groups = len(self.element_affine)
        affine = tuple(next(fresh) for _ in self.affine)
        k, p, pdot, pddot, damping, mask = (next(fresh) for _ in range(6))
        element_affine = [next(fresh) for _ in range(groups)]
        constants = [tuple(next(fresh) for _ in group) for group in self.element_constants]
        data = [next(fresh) for _ in self.data]
        return StepInputs(affine, k, p, pdot, pddot, damping, mask, element_affine, constants, data, next(fresh))
