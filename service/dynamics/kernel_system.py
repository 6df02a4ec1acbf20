"""A structure's time step assembled from element kernels (models.kernels).

Newton's unknowns Z = [u; lam]: every coordinate's acceleration (the energy form's x,
models.kernels.layout) and every multiplier. The links' node quantities are not unknowns:
each evaluation computes them exactly, in two sweeps along every chain of link elements,

    forward  (start to end)  node positions, velocities and accelerations (from the start
                             body), and each element's rows, mass force and lever;
    backward (end to start)  the node forces F_j = F_{j+1} + f_j (F_N the end multiplier),
                             the rows completed with them, and block elimination on the way
                             (models.kernels.chain_solver),

so Newton runs on Lagrange's equations of models.graph.dynamics while its linear systems are solved
in the sparse lifted form: the backward sweep, one forward substitution sweep, and the few
global unknowns (bodies, multipliers) by the condensed system's inverse.

Kernels run in chunks of CHUNK items (models.kernels.chunks), compiled once per chain
signature (service.kernels) or interpreted until then; this module only gathers their inputs
and scatters their outputs, in a few MX operations per sweep. A structure's chains of one
signature run one after another in one sweep (padded to whole chunks with absent items).
Everything here is built in milliseconds for any number of elements.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from flexmech.models.graph.structure import Structure
from flexmech.models.kernels.chain_solver import BORDER
from flexmech.models.kernels.chain_sweep import packed_size
from flexmech.models.kernels.chunks import CHUNK, Chunks, chunks
from flexmech.models.kernels.global_part import global_part, start_nodes
from flexmech.models.kernels.layout import layout_of
from flexmech.service.dynamics.kernel_groups import UNSET_AFFINE, GroupIndex, group_index
from flexmech.service.dynamics.kernel_records import Evaluation, Factors, StepInputs

NEWTON_TOLERANCE = 1e-10  # nondimensional forces
CONSTRAINT_TOLERANCE = 1e-13  # and lengths, angles
POSITION_WEIGHT = NEWTON_TOLERANCE / CONSTRAINT_TOLERANCE  # so that one tolerance serves both


def _gated(fn: ca.Function) -> ca.Function:
    """(go, inputs...) -> fn's outputs where go is 1, zeros where 0 (nothing computed)."""
    inputs = [ca.SX.sym(fn.name_in(i), fn.sparsity_in(i)) for i in range(fn.n_in())]
    idle = ca.Function(f"{fn.name()}_idle", inputs, [ca.SX.zeros(fn.sparsity_out(o)) for o in range(fn.n_out())])
    return ca.Function.if_else(f"{fn.name()}_gated", fn, idle)


class StepSystem:
    """The Newton system of a structure's step (level "position") or of its consistent
    accelerations at a start (level "acceleration"), on the chunks of its chain signatures."""

    def __init__(
        self,
        structure: Structure,
        moving: tuple[int, ...],
        level: str = "position",
        compiled: dict | None = None,
        rule: str = "interpolated",
    ):
        self.layout = layout_of(structure, rule)
        self.structure, self.moving, self.level = structure, moving, level
        self.chunks: list[Chunks] = [
            (compiled or {}).get(g.signature) or chunks(g.signature) for g in self.layout.groups
        ]
        # no compiled kernel at all: the time step may expand them (kernel_window.Stepper.gated_iteration)
        self.interpreted = not any(g.signature in (compiled or {}) for g in self.layout.groups)
        self.global_part = _gated(global_part(self.layout, moving, level))
        self.start_nodes = _gated(start_nodes(self.layout, moving))
        self.prescribed_angles: list[tuple[int | None, int | None]] = []  # (p index, moving k) of clamped starts
        self.newton_iterations: dict[tuple, ca.Function] = {}  # by the shapes of a step's inputs (full_newton)
        self.groups = [group_index(self.layout, g, self.n_z, self._prescribed_angle) for g in self.layout.groups]
        self._global_indices()

    @property
    def n_z(self) -> int:
        return self.layout.n_x + self.layout.n_lam

    # ---- constant index arrays ------------------------------------------------------------------
    def _prescribed_angle(self, chain) -> int:
        s = self.structure
        pointer = s.prescribed[chain.topology.start_body][2]
        index = s.index[pointer] if pointer else None
        key = (index, self.moving.index(index) if index in self.moving else None)
        if key not in self.prescribed_angles:
            self.prescribed_angles.append(key)
        return self.prescribed_angles.index(key)

    def _global_indices(self) -> None:
        L, s = self.layout, self.structure
        zero_affine = L.n_x + len(self.prescribed_angles)  # the zero appended to the extended affine
        for gr in self.groups:
            gr.gather_affine = [zero_affine if i >= L.n_x + UNSET_AFFINE else i for i in gr.gather_affine]
        self.z_global = list(L.x_global) + [L.n_x + j for j in range(L.n_lam)]
        n_b = len(s.bodies)
        self.newton_rows = [3 * b + c for b, c in s.free] + list(range(3 * n_b, 3 * n_b + L.n_global - len(s.free)))
        row_of = {row: k for k, row in enumerate(self.newton_rows)}
        self.border_rows = [[row_of.get(r, -1) for r in L.border_rows(c)] for c in L.chains]
        self.border_cols = [
            [col - L.n_block_unknowns if col >= 0 else -1 for col in L.border_columns(c)] for c in L.chains
        ]
        clamped = [c for g in L.groups for c in g.chains if c.topology.start == "clamped"]
        self.routed_bodies = [c.topology.start_body for c in clamped]
        self.routed_rows = [row_of.get(3 * b + 2, -1) for b in self.routed_bodies]
        self.gravity = [s.index["/gravity/0"], s.index["/gravity/1"]] if s.gravity else None
        # the condensed right-hand side: newton rows + routed rows + the chains' border rows
        n_g, n_ch = L.n_global, len(L.chains)
        T = np.zeros((n_g, len(clamped) + BORDER * n_ch))
        for r, row in enumerate(self.routed_rows):
            if row >= 0:
                T[row, r] = 1.0
        for cid, rows in enumerate(self.border_rows):
            for i, row in enumerate(rows):
                if row >= 0:
                    T[row, len(clamped) + BORDER * cid + i] = 1.0
        self.rhs_scatter = ca.DM(ca.sparsify(ca.DM(T)))
        self.routed_into_newton = ca.DM(ca.sparsify(ca.DM(T[:, : len(clamped)])))
        # from the lifted solution [blocks in order, per group, unpadded; global unknowns] to dZ
        self.lift_to_z = list(L.x_unknown) + [L.lam_index(j) for j in range(L.n_lam)]

    def extra_D(self, gi: int) -> np.ndarray:
        """(size, size x padded blocks, reverse order): identity on the dummy slots and on node
        0's definitions (their rows' derivative in themselves)."""
        g, gr = self.layout.groups[gi], self.groups[gi]
        bl, n = g.blocks, g.blocks.size
        blocks = []
        for c in g.chains:
            for j in range(c.n_blocks):
                D = np.zeros((n, n))
                if j == 0:
                    diag = list(range(bl.n_interior)) + [bl.aux(q) for q in range(6)]
                    if c.topology.start == "clamped":
                        diag.append(bl.theta)
                    D[diag, diag] = 1.0
                if j == c.n_elements:
                    D[[bl.aux(6), bl.aux(7)], [bl.aux(6), bl.aux(7)]] = 1.0
                blocks.append(D)
        blocks = blocks[::-1] + [np.zeros((n, n))] * (gr.blocks - g.n_blocks)
        return np.hstack(blocks)

    # ---- per step ---------------------------------------------------------------------------------
    def step_inputs(self, affine, k, p, pdot, pddot, damping, mask, data: list) -> StepInputs:
        """The iterations' shared inputs; data per group (n_data x padded elements)."""
        extra = [[], [], []]
        for index, m in self.prescribed_angles:
            extra[0].append(p[index] if index is not None else ca.MX(0))
            extra[1].append(pdot[m] if m is not None else ca.MX(0))
            extra[2].append(pddot[m] if m is not None else ca.MX(0))
        extended = [ca.vertcat(base, *more, 0) for base, more in zip(affine, extra)]
        gravity = p[self.gravity] if self.gravity else ca.MX.zeros(2)
        element_affine, constants = [], []
        for gr, g in zip(self.groups, self.layout.groups):
            n_c = g.signature.n_c
            element_affine.append(ca.vertcat(*[ca.reshape(v[gr.gather_affine], n_c, gr.elements) for v in extended]))
            constants.append(
                (ca.repmat(k, 1, gr.elements), ca.repmat(damping, 1, gr.elements), ca.repmat(gravity, 1, gr.elements))
            )
        xg = list(self.layout.x_global)
        cX, cV, cA = affine
        affine_global = ca.horzcat(cX[xg], cV[xg], cA[xg]) if xg else ca.MX(0, 3)
        return StepInputs(affine, k, p, pdot, pddot, damping, mask, element_affine, constants, data, affine_global)

    # ---- pieces, as MX ------------------------------------------------------------------------------
    def _forward(self, Z, go, si: StepInputs):
        """The forward sweeps: per group (next (6 x elements), packed, energies), and every
        chain's node 0 (6 x chains)."""
        Zext = ca.vertcat(Z, 0)
        starts = self.start_nodes(go, Z[self.z_global], si.affine_global, si.k, si.p, si.pdot, si.pddot)
        out = []
        for gr, g, ch, aff, (kk, damping, gravity), dat in zip(
            self.groups, self.layout.groups, self.chunks, si.element_affine, si.element_constants, si.data
        ):
            u = ca.reshape(Zext[gr.gather_u], g.signature.n_c, gr.elements)
            sweep = ch.sweep.mapaccum("sweeps", gr.elements // CHUNK, [1], [0])
            out.append(
                sweep(
                    go * ca.DM(gr.present),
                    ca.DM.zeros(6),
                    u,
                    aff,
                    kk,
                    damping,
                    gravity,
                    dat,
                    ca.DM(gr.start),
                    starts[:, gr.start_chain],
                )[1:]
            )
        return out, starts

    def evaluate(self, Z, go, si: StepInputs, kept_reverse: list) -> Evaluation:
        """The residual at Z, eliminated with kept_reverse; go = 0: nothing is computed (the
        kernels are gated off; the caller keeps its last evaluation)."""
        L = self.layout
        sweeps, starts = self._forward(Z, go, si)
        Zext = ca.vertcat(Z, 0)
        n_ch = len(L.chains)
        ys, sizes, energies = [], [], ca.MX.zeros(6)
        node0_F, ends, border, routed = [None] * n_ch, [None] * n_ch, [None] * n_ch, []
        for gr, g, ch, kept, (nxt, packed, en) in zip(self.groups, L.groups, self.chunks, kept_reverse, sweeps):
            energies = energies + ca.sum2(en)
            columns = ca.horzcat(packed, ca.DM.zeros(packed_size(g.signature), 1))
            end = ca.reshape(Zext[gr.end], 3, gr.blocks)
            backward = ch.backward.mapaccum("backward_sweeps", gr.blocks // CHUNK, [1], [0])
            _, carries, y, node = backward(
                go * ca.DM(gr.block_present),
                ca.DM.zeros(2 + g.blocks.size + BORDER),
                kept,
                columns[:, gr.this],
                ca.DM(gr.this_flags),
                columns[:, gr.prev],
                ca.DM(gr.prev_flags),
                end,
                ca.DM(gr.flags),
            )
            ys.append(y)
            sizes.append(ca.mmax(node[3, :]))
            for c, cid, b0, last in zip(g.chains, gr.chains, gr.b0, gr.last_element):
                border[cid] = carries[2 + g.blocks.size :, b0]
                node0_F[cid] = node[0:2, b0]
                if c.topology.start == "clamped":
                    routed.append(node[2, b0])
                x = c.coordinate_x(c.n_elements - 1, g.signature.degree)
                cX, _, cA = si.affine
                ends[cid] = ca.vertcat(nxt[0:2, last], nxt[4:6, last], cX[x] + si.k[0] * Z[x], cA[x] + si.k[2] * Z[x])
        starts8 = ca.vertcat(starts, ca.horzcat(*node0_F)) if n_ch else ca.MX(8, 0)
        ends6 = ca.horzcat(*ends) if n_ch else ca.MX(6, 0)
        all_rows = self.global_part(
            go, Z[self.z_global], si.affine_global, si.k, starts8, ends6, si.p, si.pdot, si.pddot, si.damping, si.mask
        )
        all_rows, global_energies = all_rows[0], all_rows[6]
        routed_v = ca.vertcat(*routed) if routed else ca.MX(0, 1)
        newton = all_rows[self.newton_rows] + ca.mtimes(self.routed_into_newton, routed_v)
        n_xg = len(L.x_global)
        norms = sizes[:]
        if n_xg:
            norms.append(ca.mmax(ca.fabs(newton[:n_xg])))
        if L.n_lam:
            scale = POSITION_WEIGHT * si.k[0] if self.level == "position" else 1.0
            norms.append(scale * ca.mmax(ca.fabs(newton[n_xg:])))
        border_v = ca.vertcat(*border) if n_ch else ca.MX(0, 1)
        rhs = all_rows[self.newton_rows] + ca.mtimes(self.rhs_scatter, ca.vertcat(routed_v, border_v))
        norm = ca.mmax(ca.vertcat(*norms)) if norms else ca.MX(0)
        return Evaluation(ys, rhs, all_rows, routed_v, energies, global_energies, norm)

    def factorize(self, Z, si: StepInputs) -> Factors:
        """The factors of the Newton system at Z."""
        L = self.layout
        one = ca.MX(1)
        sweeps, starts = self._forward(Z, one, si)
        Zext = ca.vertcat(Z, 0)
        n_ch = len(L.chains)
        node0_F, ends, locals_ = [None] * n_ch, [None] * n_ch, []
        for gr, g, (nxt, packed, _end) in zip(self.groups, L.groups, sweeps):
            n_c = g.signature.n_c
            kinematics = ca.horzcat(starts[:, gr.chains], nxt)[:, gr.node_columns]  # (6, blocks) in order
            lam_end = ca.horzcat(Zext[gr.end_of_block], Zext[[i + 1 if i < self.n_z else i for i in gr.end_of_block]]).T
            F = ca.mtimes(packed[n_c : n_c + 2, :], ca.DM(gr.force_sum)) + lam_end
            nodes = ca.vertcat(kinematics, F)  # (8, padded blocks) in order
            at = gr.element_node + [0] * (gr.elements - g.n_elements)
            after = [q + 1 for q in gr.element_node] + [0] * (gr.elements - g.n_elements)
            u = ca.reshape(Zext[gr.gather_u], n_c, gr.elements)
            locals_.append(ca.vertcat(u, nodes[:, at], nodes[:, after]))
            for c, cid in zip(g.chains, gr.chains):
                last = c.first_block + c.n_elements
                node0_F[cid] = F[:, c.first_block]
                x = c.coordinate_x(c.n_elements - 1, g.signature.degree)
                cX, _, cA = si.affine
                ends[cid] = ca.vertcat(
                    kinematics[0:2, last], kinematics[4:6, last], cX[x] + si.k[0] * Z[x], cA[x] + si.k[2] * Z[x]
                )
        starts8 = ca.vertcat(starts, ca.horzcat(*node0_F)) if n_ch else ca.MX(8, 0)
        ends6 = ca.horzcat(*ends) if n_ch else ca.MX(6, 0)
        out = self.global_part(
            one, Z[self.z_global], si.affine_global, si.k, starts8, ends6, si.p, si.pdot, si.pddot, si.damping, si.mask
        )
        J_global, start_C, start_W = out[1], out[3], out[4]
        A = ca.densify(J_global)
        kept_reverse, kept_forward = [], []
        for gi, (gr, local) in enumerate(zip(self.groups, locals_)):
            kept, carries = self._factor_group(gi, local, si, start_C, start_W)
            kept_reverse.append(kept)
            kept_forward.append(kept[:, gr.forward])
            for cid, b0 in zip(gr.chains, gr.b0):
                S = ca.reshape(carries[-BORDER * BORDER :, b0], BORDER, BORDER)
                A = self._add_border(A, S, cid)
        inverse = ca.inv(A) if L.n_global else ca.MX(0, 0)
        return Factors(kept_reverse, kept_forward, inverse)

    def _factor_group(
        self, gi: int, local: ca.MX, si: StepInputs, start_C: ca.MX, start_W: ca.MX
    ) -> tuple[ca.MX, ca.MX]:
        """(kept, carries) of group gi's factor sweep: its elements' Jacobians at their local
        unknowns, eliminated block by block along its chains (reverse order)."""
        gr, g, ch = self.groups[gi], self.layout.groups[gi], self.chunks[gi]
        kk, damping, gravity = si.element_constants[gi]
        sig, n = g.signature, g.blocks.size
        jacobian = ch.jacobian.map(gr.elements // CHUNK)
        _, J = jacobian(ca.DM(gr.present), local, si.element_affine[gi], kk, damping, gravity, si.data[gi])
        J_cols = ca.horzcat(
            ca.reshape(ca.densify(J), sig.n_rows * sig.n_local, gr.elements),
            ca.DM.zeros(sig.n_rows * sig.n_local, 1),
        )

        def per_block(index):
            return ca.reshape(J_cols[:, index], sig.n_rows, sig.n_local * gr.blocks)

        extra_C, extra_W = self._extra_C_W(gr, g, start_C, start_W)
        carry0 = ca.DM.zeros(n * n + 2 * n * BORDER + BORDER * BORDER)
        factor = ch.factor.mapaccum("factor_sweeps", gr.blocks // CHUNK, [1], [0])
        _, carries, kept = factor(
            ca.DM(gr.block_present),
            carry0,
            per_block(gr.this),
            ca.DM(gr.this_flags),
            per_block(gr.prev),
            ca.DM(gr.prev_flags),
            ca.DM(self.extra_D(gi)),
            extra_C,
            extra_W,
            ca.DM(gr.flags),
        )
        return kept, carries

    def _add_border(self, A: ca.MX, S: ca.MX, chain: int) -> ca.MX:
        rows, cols = self.border_rows[chain], self.border_cols[chain]
        r_keep = [i for i, r in enumerate(rows) if r >= 0]
        c_keep = [j for j, c in enumerate(cols) if c >= 0]
        if r_keep and c_keep:
            rr, cc = [rows[i] for i in r_keep], [cols[j] for j in c_keep]
            A[rr, cc] = A[rr, cc] + S[r_keep, c_keep]
        return A

    def _extra_C_W(self, gr: GroupIndex, g, start_C: ca.MX, start_W: ca.MX):
        """(size x BORDER blocks, BORDER x size blocks), reverse order: node 0's definitions
        against the start body's unknowns, the start body's rows against F_0; the end
        conditions' rows against node N (rho, or a at a start) and theta_N, lam_rot in theta_N's row."""
        bl, n = g.blocks, g.blocks.size
        C = ca.MX.zeros(n, BORDER * gr.blocks)
        W = ca.MX.zeros(BORDER, n * gr.blocks)
        for c, cid, b0 in zip(g.chains, gr.chains, gr.b0):
            bN = b0 - c.n_elements  # reverse order: B_N comes n_elements before B_0
            C[[bl.aux(q) for q in range(6)], list(range(b0 * BORDER, b0 * BORDER + 3))] = start_C[
                :, 3 * cid : 3 * cid + 3
            ]
            W[[0, 1, 2], [b0 * n + bl.aux(6), b0 * n + bl.aux(7)]] = start_W[:, 2 * cid : 2 * cid + 2]
            node = (bl.aux(0), bl.aux(1)) if self.level == "position" else (bl.aux(4), bl.aux(5))
            W[3, bN * n + node[0]] = 1
            W[4, bN * n + node[1]] = 1
            if c.topology.end == "clamped":
                W[5, bN * n + bl.theta] = 1
                C[bl.theta, bN * BORDER + 5] = 1
        return C, W

    def solve(self, ev: Evaluation, go, factors: Factors) -> ca.MX:
        """dZ such that the Newton step is Z - dZ (zeros where go = 0)."""
        L = self.layout
        x_global = ca.mtimes(factors.inverse, ev.rhs) if L.n_global else ca.MX(0, 1)
        x_ext = ca.vertcat(x_global, 0)
        parts = []
        for gr, g, ch, kept, y in zip(self.groups, L.groups, self.chunks, factors.kept_forward, ev.y):
            border = []
            for c, cid in zip(g.chains, gr.chains):
                cols = [col if col >= 0 else L.n_global for col in self.border_cols[cid]]
                border += cols * c.n_blocks
            border += [L.n_global] * (BORDER * (gr.blocks - g.n_blocks))
            x_border = ca.reshape(x_ext[border], BORDER, gr.blocks)
            present = ca.DM(gr.block_present[:, gr.forward])
            substitute = ch.substitute.mapaccum("substitute_sweeps", gr.blocks // CHUNK, [1], [0])
            _, _, x = substitute(
                go * present,
                ca.DM.zeros(g.blocks.size),
                kept,
                y[:, gr.forward],
                x_border,
                ca.DM(gr.flags[:, gr.forward]),
            )
            parts.append(ca.vec(x[:, : g.n_blocks]))
        return ca.vertcat(*parts, x_global)[self.lift_to_z]
