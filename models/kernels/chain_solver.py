"""Block elimination along chains of link elements (models.kernels.link_chain): the sparse
factorization of a step's Newton system and its solutions, as kernels that a structure runs
by mapaccum over the blocks of all its chains in a row.

A chain of N elements has N + 1 blocks B_0..B_N of `size` unknowns each,

    B_j = [interior coordinates of element j-1 (n_c - 2) | theta_j | rho_j v_j a_j F_j (8)]

with rows in the same order (gen rows of the coordinates; rho, v, a: node j's definitions
from element j-1 or, at j = 0, from the start body; F_j's recursion from element j). B_0's
interior part, a clamped start's theta_0 (it is the start body's angle) and B_N's F_N (it
is the end multiplier) are dummies: an identity row and column. Element j couples B_j and
B_{j+1}. A chain's ends couple to BORDER global unknowns and rows:

    columns  [start body x, y, angle | lambda_x, lambda_y, lambda_rotation]
    rows     [start body x, y, angle | end conditions x, y, rotation]

Blocks are eliminated from the chain's end (B_N first): the backward sweep that completes the
residual (the node forces F_j = F_{j+1} + f_j, that each element's coordinates feel through
its end) eliminates on the way, and one forward sweep substitutes back. The start border
enters at the last block eliminated; the end border is carried along (its columns C and rows
W fill in), and the chain's condensed border block is S = -sum W D^-1 C.

Kernels, per block j, the chains' blocks one after another, in reverse for factor and
backward, in order for substitute:
  factor     element j's and element j-1's Jacobians (zero where there is none), the block's
             extra parts (caps, dummies) -> the factors kept for the solves; the carry passes
             the Schur complement on to block j-1; at a chain's first block it holds S.
  backward   the elements' packed sweep outputs (rows without their end force, f, the lever
             dDelta/dc), the end's multipliers -> y_j, node = (F_j, a clamped start's theta_0 row,
             the block's residual's size), and the border rows' right-hand side (in the carry, at
             the chain's first block)
  substitute y_j, x_{j-1} (the carry) and the chain's border solution -> x_j

Each element's Jacobian arrives with two flags: `clamped` (the first element of a link with a
clamped start: its theta_0 column and row are the border's angle) and `last` (the last
element of a link: its F_{e+1} column is the border's lambda).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache, cached_property

import casadi as ca
import numpy as np

from flexmech.models.kernels.chain_signature import NODE, ChainSignature

BORDER = 6
FLAGS = ("first", "last")  # per block: the chain's first block (B_0), its last (B_N)
ELEMENT_FLAGS = ("present", "clamped", "last")  # per element slot of a block


@dataclass(frozen=True)
class BlockLayout:
    """Where an element's unknowns and rows sit in its two blocks (0: B_j, 1: B_{j+1})."""

    signature: ChainSignature

    @property
    def n_interior(self) -> int:
        return self.signature.n_c - 2

    @property
    def size(self) -> int:
        return self.signature.n_c + 7

    @property
    def theta(self) -> int:
        return self.n_interior

    def aux(self, j: int) -> int:
        """Slot of node quantity j (rho 0-1, v 2-3, a 4-5, F 6-7)."""
        return self.n_interior + 1 + j

    @property
    def node(self) -> list[int]:
        return [self.theta] + [self.aux(j) for j in range(NODE)]

    @property
    def coupling_rows(self) -> list[int]:
        """Rows of B_j that element j reaches into B_{j+1} with: theta_j's gen row and F_j's."""
        return [self.theta, self.aux(6), self.aux(7)]

    @cached_property
    def unknown_slots(self) -> list[tuple[int, int]]:
        """(block, slot) of each of an element's n_local unknowns."""
        p, n_c = self.signature.degree, self.signature.n_c
        slots = []
        for i in range(n_c):
            if i == 0:
                slots.append((0, self.theta))
            elif i == p:
                slots.append((1, self.theta))
            else:
                slots.append((1, i - 1 if i < p else i - 2))
        slots += [(0, self.aux(j)) for j in range(NODE)] + [(1, self.aux(j)) for j in range(NODE)]
        return slots

    @cached_property
    def row_slots(self) -> list[tuple[int, int]]:
        """(block, row slot) of each of an element's n_rows rows: gen by its coordinate's
        slot, F_j's rows in B_j, rho, v, a of node j+1 in B_{j+1}."""
        rows = self.unknown_slots[: self.signature.n_c]
        rows += [(0, self.aux(6)), (0, self.aux(7))]
        rows += [(1, self.aux(j)) for j in range(6)]
        return rows

    def selection(self, block: int, by: str) -> np.ndarray:
        """(size, n) 0/1: the element's unknowns (by="unknowns") or rows in `block`."""
        slots = self.unknown_slots if by == "unknowns" else self.row_slots
        out = np.zeros((self.size, len(slots)))
        for i, (b, s) in enumerate(slots):
            if b == block:
                out[s, i] = 1.0
        return out


def _lu(D: ca.SX) -> ca.SX:
    """Doolittle LU without pivoting, packed: strictly lower L (unit diagonal) and upper U.
    A block's pivots are a mass plus stiffness (its coordinates), then near 1 (its node
    quantities' definitions), or 1 (dummies): no pivoting is needed."""
    A = ca.SX(D)
    for k in range(D.shape[0] - 1):  # a column and a rank-one update per pivot, as matrix operations
        A[k + 1 :, k] = A[k + 1 :, k] / A[k, k]
        A[k + 1 :, k + 1 :] = A[k + 1 :, k + 1 :] - ca.mtimes(A[k + 1 :, k], A[k, k + 1 :])
    return A


def lu_solve(LU: ca.SX, b: ca.SX) -> ca.SX:
    """D^-1 b for the packed factors of _lu (b: n x m)."""
    solve = _column_solver(LU.shape[0], transposed=False)
    return ca.horzcat(*[solve(LU, b[:, c]) for c in range(b.shape[1])])


def lu_solve_transposed(LU: ca.SX, b: ca.SX) -> ca.SX:
    """D^-T b (b: n x m)."""
    solve = _column_solver(LU.shape[0], transposed=True)
    return ca.horzcat(*[solve(LU, b[:, c]) for c in range(b.shape[1])])


@cache
def _column_solver(n: int, transposed: bool) -> ca.Function:
    """(LU, b) -> D^-1 b (or D^-T b) for one column b: written out once and called (inlined)
    per column, the same expressions as writing out every column, built many times faster."""
    LU, b = ca.SX.sym("LU", n, n), ca.SX.sym("b", n)
    y = [b[i] for i in range(n)]
    if transposed:
        for i in range(n):  # U^T
            for j in range(i):
                y[i] = y[i] - LU[j, i] * y[j]
            y[i] = y[i] / LU[i, i]
        for i in reversed(range(n)):  # L^T
            for j in range(i + 1, n):
                y[i] = y[i] - LU[j, i] * y[j]
    else:
        for i in range(n):
            for j in range(i):
                y[i] = y[i] - LU[i, j] * y[j]
        for i in reversed(range(n)):
            for j in range(i + 1, n):
                y[i] = y[i] - LU[i, j] * y[j]
            y[i] = y[i] / LU[i, i]
    return ca.Function("lu_column_solve", [LU, b], [ca.vertcat(*y)])


class _Split:
    """An element's Jacobian J (n_rows x n_local) in its two blocks and the border, with a
    clamped start's theta_0 and the last element's F_{e+1} routed to the border:
    J00 (B_j rows x B_j cols), J01, J10, J11, and the border parts C0, C1 (block rows x border
    columns), W0, W1 (border rows x block columns), S (border x border)."""

    def __init__(self, layout: BlockLayout, J: ca.SX, flags: ca.SX):
        sig = layout.signature
        present, clamped, last = flags[0], flags[1], flags[2]
        n_c = sig.n_c
        theta_out = np.zeros(layout.size)
        theta_out[layout.theta] = 1.0
        force_out = np.zeros(layout.size)
        force_out[layout.aux(6) : layout.aux(8)] = 1.0
        R0, R1 = (ca.DM(layout.selection(b, "rows")) for b in (0, 1))
        C0, C1 = (ca.DM(layout.selection(b, "unknowns")) for b in (0, 1))
        keep0 = 1 - clamped * ca.DM(theta_out)  # B_j slots that stay (rows and columns)
        keep1 = 1 - last * ca.DM(force_out)  # B_{j+1} columns that stay
        theta_row = np.zeros((BORDER, sig.n_rows))
        theta_row[2, 0] = 1.0
        theta_col = np.zeros((sig.n_local, BORDER))
        theta_col[0, 2] = 1.0
        force_col = np.zeros((sig.n_local, BORDER))
        F_next = n_c + NODE + 6
        force_col[F_next, 3] = force_col[F_next + 1, 4] = 1.0
        border_row = clamped * ca.DM(theta_row)  # (BORDER, n_rows)
        border_col = clamped * ca.DM(theta_col) + last * ca.DM(force_col)  # (n_local, BORDER)
        J = present * J
        rows0 = ca.mtimes(ca.diag(keep0), ca.mtimes(R0, J))
        rows1 = ca.mtimes(R1, J)
        cols0, cols1 = ca.mtimes(C0.T, ca.diag(keep0)), ca.mtimes(C1.T, ca.diag(keep1))
        border = ca.mtimes(border_row, J)
        self.J00, self.J01 = ca.mtimes(rows0, cols0), ca.mtimes(rows0, cols1)
        self.J10, self.J11 = ca.mtimes(rows1, cols0), ca.mtimes(rows1, cols1)
        self.C0, self.C1 = ca.mtimes(rows0, border_col), ca.mtimes(rows1, border_col)
        self.W0, self.W1 = ca.mtimes(border, cols0), ca.mtimes(border, cols1)
        self.S = ca.mtimes(border, border_col)


@dataclass(frozen=True)
class SolverFunctions:
    factor: ca.Function
    backward: ca.Function
    substitute: ca.Function
    factor_size: int  # numbers kept per block for the solves


def _unpack(k: ca.SX, sizes: list[tuple[int, int]]) -> list[ca.SX]:
    parts, o = [], 0
    for rows, cols in sizes:
        parts.append(ca.reshape(k[o : o + rows * cols], rows, cols))
        o += rows * cols
    return parts


def solver_functions(signature: ChainSignature) -> SolverFunctions:
    layout = BlockLayout(signature)
    factor, kept_size = _factor_function(signature, layout)
    return SolverFunctions(
        factor,
        _backward_function(signature, layout, kept_size),
        _substitute_function(signature, layout, kept_size),
        kept_size,
    )


def _kept(layout: BlockLayout, k: ca.SX) -> list[ca.SX]:
    """A block's kept factors: LU of D, D^-1 L, D^-1 C, W D^-1, U."""
    n, nb = layout.size, BORDER
    return _unpack(k, [(n, n), (n, len(layout.node)), (n, nb), (nb, n), (len(layout.coupling_rows), n)])


def _factor_function(signature: ChainSignature, layout: BlockLayout) -> tuple[ca.Function, int]:
    """Blocks in reverse: (carry, J, element, J_prev, element_prev, extra_D, extra_C, extra_W,
    flags) -> (next carry, kept factors)."""
    n, nb, n_rows, n_local = layout.size, BORDER, signature.n_rows, signature.n_local
    node, coupling = layout.node, layout.coupling_rows
    flags = ca.SX.sym("flags", len(FLAGS))
    keep = 1 - flags[1]  # the carry from the next block (none at a chain's last block)
    J_this, J_prev = ca.SX.sym("J", n_rows, n_local), ca.SX.sym("J_prev", n_rows, n_local)
    f_this, f_prev = ca.SX.sym("element", len(ELEMENT_FLAGS)), ca.SX.sym("element_prev", len(ELEMENT_FLAGS))
    extra_D, extra_C, extra_W = ca.SX.sym("extra_D", n, n), ca.SX.sym("extra_C", n, nb), ca.SX.sym("extra_W", nb, n)
    carry_D, carry_C = ca.SX.sym("carry_D", n, n), ca.SX.sym("carry_C", n, nb)
    carry_W, carry_S = ca.SX.sym("carry_W", nb, n), ca.SX.sym("carry_S", nb, nb)
    this, prev = _Split(layout, J_this, f_this), _Split(layout, J_prev, f_prev)
    # block j: element j's rows and columns in B_j, element j-1's in B_j (its second block)
    D = keep * carry_D + this.J00 + prev.J11 + extra_D
    C = keep * carry_C + this.C0 + prev.C1 + extra_C
    W = keep * carry_W + this.W0 + prev.W1 + extra_W
    S = keep * carry_S + this.S
    LU = _lu(D)
    # back substitution: x_j = D^-1 (b_j - L_j x_{j-1} - C x_border), L_j = element j-1's B_j rows x B_{j-1} cols
    L = prev.J10[:, node]
    Y_L = lu_solve(LU, L)
    Y_C = lu_solve(LU, C)
    WY = lu_solve_transposed(LU, W.T).T  # W D^-1
    # to block j-1: U = element j-1's B_{j-1} rows x B_j cols (rows theta_{j-1}, F_{j-1} only)
    U = prev.J01[coupling, :]
    next_D = ca.SX.zeros(n, n)
    next_D[coupling, node] = -ca.mtimes(U, Y_L)
    next_C = ca.SX.zeros(n, nb)
    next_C[coupling, :] = -ca.mtimes(U, Y_C)
    next_W = ca.SX.zeros(nb, n)
    next_W[:, node] = -ca.mtimes(WY, L)
    next_S = S - ca.mtimes(W, Y_C)
    kept = ca.vertcat(ca.vec(LU), ca.vec(Y_L), ca.vec(Y_C), ca.vec(WY), ca.vec(U))
    factor = ca.Function(
        f"{signature.key}_factor",
        [
            ca.vertcat(ca.vec(carry_D), ca.vec(carry_C), ca.vec(carry_W), ca.vec(carry_S)),
            J_this,
            f_this,
            J_prev,
            f_prev,
            extra_D,
            extra_C,
            extra_W,
            flags,
        ],
        [ca.vertcat(ca.vec(next_D), ca.vec(next_C), ca.vec(next_W), ca.vec(next_S)), kept],
        ["carry", "J", "element", "J_prev", "element_prev", "extra_D", "extra_C", "extra_W", "flags"],
        ["next", "kept"],
        {"cse": True},
    )
    return factor, kept.numel()


def _backward_function(signature: ChainSignature, layout: BlockLayout, kept_size: int) -> ca.Function:
    """Blocks in reverse: complete the rows with the node forces, eliminate. (carry, kept,
    packed, element, packed_prev, element_prev, end, flags) -> (next carry, y, node)."""
    n, nb, n_c, coupling = layout.size, BORDER, signature.n_c, layout.coupling_rows
    flags = ca.SX.sym("flags", len(FLAGS))
    last_block = flags[1]
    keep = 1 - last_block
    f_this, f_prev = ca.SX.sym("element", len(ELEMENT_FLAGS)), ca.SX.sym("element_prev", len(ELEMENT_FLAGS))
    k = ca.SX.sym("kept", kept_size)
    LU_k, _, _, WY_k, U_k = _kept(layout, k)
    # element outputs of the forward sweep, packed: gen rows without the end force, f, lever dDelta/dc
    packed_this, packed_prev = ca.SX.sym("packed", 3 * n_c + 2), ca.SX.sym("packed_prev", 3 * n_c + 2)
    gen_this, force_this = packed_this[:n_c], packed_this[n_c : n_c + 2]
    lever_this = ca.reshape(packed_this[n_c + 2 :], 2, n_c)
    gen_prev, lever_prev = packed_prev[:n_c], ca.reshape(packed_prev[n_c + 2 :], 2, n_c)
    # lambda_end (x, y) and lambda_rot at a chain's last block (zeros elsewhere)
    end = ca.SX.sym("end", 3)
    extra_b = ca.SX.zeros(n)
    extra_b[layout.theta] = end[2]
    carry_F, carry_b, carry_border = ca.SX.sym("carry_F", 2), ca.SX.sym("carry_b", n), ca.SX.sym("carry_border", nb)
    # node forces: F_{j+1} from the carry (at B_N: none); F_j = F_{j+1} + f_j, and F_N = lambda_end
    F_next = keep * carry_F
    F_j = last_block * end[0:2] + keep * (F_next + force_this)
    rows_this = f_this[0] * (gen_this + ca.mtimes(lever_this.T, F_next))  # element j's gen rows
    rows_prev = f_prev[0] * (gen_prev + ca.mtimes(lever_prev.T, F_j))  # element j-1's
    sel0 = layout.selection(0, "rows")[:, :n_c]
    sel1 = layout.selection(1, "rows")[:, :n_c]
    # B_j's rows: element j-1's in B_j (its interior, theta_j), element j's theta_j (unless it is
    # a clamped start's: then it is the start body's angle row, a border row)
    b = ca.mtimes(ca.DM(sel1), rows_prev) + (1 - f_this[1]) * ca.mtimes(ca.DM(sel0), rows_this) + extra_b
    routed = f_this[1] * rows_this[0]
    b_tilde = b + keep * carry_b
    y = lu_solve(LU_k, b_tilde)
    next_b = ca.SX.zeros(n)
    next_b[coupling] = -ca.mtimes(U_k, y)
    border_rows = keep * carry_border - ca.mtimes(WY_k, b_tilde)
    return ca.Function(
        f"{signature.key}_backward",
        [ca.vertcat(carry_F, carry_b, carry_border), k, packed_this, f_this, packed_prev, f_prev, end, flags],
        [ca.vertcat(F_j, next_b, border_rows), y, ca.vertcat(F_j, routed, ca.mmax(ca.fabs(b)))],
        ["carry", "kept", "packed", "element", "packed_prev", "element_prev", "end", "flags"],
        ["next", "y", "node"],
        {"cse": True},
    )


def _substitute_function(signature: ChainSignature, layout: BlockLayout, kept_size: int) -> ca.Function:
    """Blocks in order: (x_prev, kept, y, x_border, flags) -> (x, x)."""
    n, nb, node = layout.size, BORDER, layout.node
    flags = ca.SX.sym("flags", len(FLAGS))
    k = ca.SX.sym("kept", kept_size)
    _, Y_L_k, Y_C_k, _, _ = _kept(layout, k)
    x_prev, x_border, y_in = ca.SX.sym("x_prev", n), ca.SX.sym("x_border", nb), ca.SX.sym("y", n)
    x = y_in - ca.mtimes(Y_L_k, (1 - flags[0]) * x_prev[node]) - ca.mtimes(Y_C_k, x_border)
    return ca.Function(
        f"{signature.key}_substitute",
        [x_prev, k, y_in, x_border, flags],
        [x, x],
        ["carry", "kept", "y", "x_border", "flags"],
        ["next", "x"],
        {"cse": True},
    )
