"""The global part of a structure's kernel system: the bodies (inertia, loads, weights, and the
contact pairs' potential, friction and damping: models.contact.pair_forces), the elements of
families other than links by elements (their energies and equalities), and the caps that tie
each chain of link elements to its bodies. Its unknowns are few (body
coordinates and multipliers), so it is one small graph per structure.

One Lagrangian gives every row:

    Lag = V(d, q) + sum_e lam_e . g_e(d, q)                      loads, weights, other elements
        + sum_chains F_0 . start(d_i) + lam_end . (r_N - target(d_j)) + lam_rot (theta_N - d_j[2])

so that a body coordinate's row is its inertia (Lagrange's equations of the bodies' kinetic
energy) plus dLag/dd, an equality's row is g / kx (kx: dX/du, so that the rows of
position-level constraints scale like accelerations), and each chain's node-0 quantities are
defined by rho_0 = start / kx, v_0 = start', a_0 = start''. A link's start F_0 . start(d_i)
is the force the link's start puts on its body; F_N is lam_end (models.kernels.chain_solver).

Rows of every body coordinate are given, free or prescribed: a prescribed one's row is the
force its motion needs (with the chains' border rows added: the glue's business).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from flexmech.models.contact.pair_forces import contact_forces
from flexmech.models.elements import FAMILIES
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.loads import kinetic_energy, load_potential
from flexmech.models.kernels.chain_signature import data_layout
from flexmech.models.kernels.layout import KernelLayout
from flexmech.models.kernels.link_data import link_data

INPUTS = ("uG", "affine", "k", "starts", "ends", "p", "pdot", "pddot", "damping", "mask")
OUTPUTS = ("rows", "J", "start_rows", "start_C", "start_W", "end_theta", "energies")
# the held potential: without the varying loads; power: the varying loads' (the input)
ENERGIES = ("kinetic", "potential", "held", "power", "friction_power", "contact_damping_power")


def global_part(layout: KernelLayout, moving: tuple[int, ...], level: str = "position") -> ca.Function:
    """(uG, affine (global coordinates x 3: cX, cV, cA), k (kx, kv, ka, k_rho), starts (8 x
    chains: rho, v, a, F of node 0), ends (6 x chains: rho and a of node N, theta_N's value and
    acceleration), p, pdot, pddot, damping, mask) -> (rows (3 per body, then the other
    elements' own variables, then every multiplier), J (the Newton rows' derivative in uG),
    start_rows (6 x chains: node 0's definitions), start_C (6 x 3 chains: their derivative in
    the start body's unknowns), start_W (3 x 2 chains: the start body's rows' derivative in
    F_0), end_theta (chains: lam_rot, to add to theta_N's row), energies (ENERGIES)).

    level "position": equalities held at position level, rows g / kx (time steps); level
    "acceleration": their second derivatives (consistent accelerations at a start)."""
    s = layout.structure
    ctx = AssemblyContext(s)
    n_b, n_xg, n_ch = len(s.bodies), len(layout.x_global), len(layout.chains)
    uG, affine, k = ca.SX.sym("uG", layout.n_global), ca.SX.sym("affine", n_xg, 3), ca.SX.sym("k", 4)
    starts, ends = ca.SX.sym("starts", 8, n_ch), ca.SX.sym("ends", 6, n_ch)
    pdot, pddot = ca.SX.sym("pdot", len(moving)), ca.SX.sym("pddot", len(moving))
    damping, mask, p = ca.SX.sym("damping"), ca.SX.sym("mask", ctx.p.numel()), ctx.p
    kx, kv, ka = k[0], k[1], k[2]
    u_x, lam = uG[:n_xg], uG[n_xg:]
    X, V, A = affine[:, 0] + kx * u_x, affine[:, 1] + kv * u_x, affine[:, 2] + ka * u_x
    # every body coordinate (and other element's own variable) as a symbol, then replaced by its
    # value: rows of prescribed coordinates too
    n_own = n_xg - len(s.free)
    Q, Qd, Qdd = (ca.SX.sym(name, 3 * n_b + n_own) for name in ("Q", "Qd", "Qdd"))
    D, Dd = Q[: 3 * n_b], Qd[: 3 * n_b]
    d = [D[3 * b : 3 * b + 3] for b in range(n_b)]
    potential, lagrangian, own_rows, equalities = _elements(ctx, layout, d, Q[3 * n_b :], lam)
    caps, start_rows, end_theta = _chain_ends(ctx, layout, d, lam, starts, ends, (Q, Qd, Qdd), k, level, equalities)
    equality_rows = [_held(row, level, kx, Q, Qd, Qdd) for row in equalities]
    kinetic, mass, inertia = _body_inertia(ctx, d, [Dd[3 * b : 3 * b + 3] for b in range(n_b)], Q, Qd, Qdd)
    pairs = contact_forces(ctx, d, [Dd[3 * b : 3 * b + 3] for b in range(n_b)])
    q_rows = (
        inertia
        + damping * ca.mtimes(mass, Qd)
        + ca.gradient(lagrangian + caps, Q)
        - ca.vertcat(*pairs.wrenches, ca.SX.zeros(n_own))
    )
    # the varying loads: V enters linearly in them; their power through the free coordinates
    free = np.zeros(3 * n_b + n_own)
    free[[3 * b + c for b, c in s.free]] = 1.0
    held = potential - ca.dot(ca.gradient(potential, p), mask * p)
    power = -ca.dot(ca.jtimes(ca.gradient(potential, Q), p, mask * p), ca.DM(free) * Qd)
    rows = ca.vertcat(q_rows, ca.vertcat(*equality_rows) if equality_rows else ca.SX(0, 1))
    values, rates, accelerations = _body_values(ctx, moving, X, V, A, pdot, pddot)
    old = ca.vertcat(Q, Qd, Qdd)
    new = ca.vertcat(values, X[len(s.free) :], rates, V[len(s.free) :], accelerations, A[len(s.free) :])
    starts_rows = ca.vertcat(*start_rows) if start_rows else ca.SX(0, 1)
    rows, starts_rows, kinetic, potential, held, power, friction_power, contact_damping_power = ca.substitute(
        [rows, starts_rows, kinetic, potential, held, power, pairs.friction_power, pairs.damping_power], [old], [new]
    )
    inputs = [uG, affine, k, starts, ends, p, pdot, pddot, damping, mask]
    energies = [kinetic, potential, held, power, friction_power, contact_damping_power]
    outputs = _outputs(layout, uG, starts, rows, starts_rows, end_theta, energies)
    fn = ca.Function(f"global_part_{level}", inputs, outputs, list(INPUTS), list(OUTPUTS), {"cse": True})
    if fn.has_free():
        raise RuntimeError(f"global part has free symbols {fn.get_free()}")
    return fn


def _body_inertia(ctx, d, d_rates, Q, Qd, Qdd) -> tuple[ca.SX, ca.SX, ca.SX]:
    """(kinetic energy, mass matrix, inertia rows): Lagrange's equations of the bodies' kinetic
    energy, in the coordinates Q and their rates Qd, Qdd."""
    kinetic = kinetic_energy(ctx, d, d_rates)
    momentum = ca.gradient(kinetic, Qd)
    mass = ca.jacobian(momentum, Qd)
    inertia = ca.mtimes(mass, Qdd) + ca.jtimes(momentum, Q, Qd) - ca.gradient(kinetic, Q)
    return kinetic, mass, inertia


def _outputs(layout: KernelLayout, uG, starts, rows, starts_rows, end_theta: list, energies: list) -> list[ca.SX]:
    """The part's outputs (OUTPUTS) from its rows in the unknowns: the Newton rows' derivative,
    the chains' start blocks and end angles, and the energies (ENERGIES)."""
    s = layout.structure
    n_b = len(s.bodies)
    newton_rows = ca.vertcat(*[rows[3 * b + c] for b, c in s.free], rows[3 * n_b :])
    start_C, start_W = _start_blocks(layout, uG, rows, starts_rows, starts)
    return [
        rows,
        ca.jacobian(newton_rows, uG),
        starts_rows,
        ca.horzcat(*start_C) if start_C else ca.SX(6, 0),
        ca.horzcat(*start_W) if start_W else ca.SX(3, 0),
        ca.vertcat(*end_theta) if end_theta else ca.SX(0, 1),
        ca.vertcat(*energies),
    ]


def _chain_ends(ctx, layout: KernelLayout, d, lam, starts, ends, Qs, k, level: str, equalities: list):
    """Per chain: its start node's definitions (rows) and the cap terms that tie its node 0 and
    node N to the bodies; its end conditions replace their entries of `equalities` (as
    ("done", row)). Returns (caps, start rows, end_theta: lam_rot of a clamped end)."""
    Q, Qd, Qdd = Qs
    kx, k_rho = k[0], k[3]
    caps, start_rows, end_theta = ca.SX(0), [], []
    for c, chain in enumerate(layout.chains):
        t = chain.topology
        start = _start_point(ctx, t, d)
        node = starts[:, c]
        caps = caps + ca.dot(node[6:8], start)
        rate = ca.jtimes(start, Q, Qd)
        acceleration = ca.jtimes(rate, Q, Qd) + ca.jtimes(start, Q, Qdd)
        start_rows.append(ca.vertcat(node[0:2] - start / k_rho, node[2:4] - rate, node[4:6] - acceleration))
        end_rows, end_term = _end(ctx, chain, d, lam)
        caps = caps + end_term
        m = chain.multiplier_offset
        if level == "position":  # r_N - target, theta_N - d_j[2]: the values at the step's end
            values = ca.vertcat(k_rho * ends[0:2, c], ends[4, c])
            end_rows = [(values[j] - end_rows[j]) / kx for j in range(len(end_rows))]
        else:  # their second derivatives
            values = ca.vertcat(ends[2:4, c], ends[5, c])
            end_rows = [values[j] - _second_derivative(end_rows[j], Q, Qd, Qdd) for j in range(len(end_rows))]
        equalities[m : m + len(end_rows)] = [("done", row) for row in end_rows]
        end_theta.append(lam[m + 2] if t.end == "clamped" else ca.SX(0))
    return caps, start_rows, end_theta


def _held(row, level: str, kx, Q, Qd, Qdd) -> ca.SX:
    """An equality's Newton row: g / kx at position level, its second derivative at acceleration
    level; ("done", row) is one already written (a chain's end)."""
    if isinstance(row, tuple):
        return row[1]
    if level == "position":
        return row / kx
    return _second_derivative(row, Q, Qd, Qdd)


def _start_blocks(layout: KernelLayout, uG, rows, starts_rows, starts) -> tuple[list, list]:
    """Per chain: its start rows' derivative in the start body's unknowns (6 x 3), and the
    start body's rows' derivative in the chain's F_0 (3 x 2)."""
    s = layout.structure
    start_C, start_W = [], []
    for c, chain in enumerate(layout.chains):
        b = chain.topology.start_body
        block = starts_rows[6 * c : 6 * c + 6]
        start_C.append(
            ca.horzcat(
                *[
                    ca.jacobian(block, uG[layout.x_global.index(s.free.index((b, q)))])
                    if (b, q) in s.free
                    else ca.SX.zeros(6, 1)
                    for q in range(3)
                ]
            )
        )
        start_W.append(ca.jacobian(rows[3 * b : 3 * b + 3], starts[6:8, c]))
    return start_C, start_W


def _second_derivative(expr: ca.SX, Q: ca.SX, Qd: ca.SX, Qdd: ca.SX) -> ca.SX:
    rate = ca.jtimes(expr, Q, Qd)
    return ca.jtimes(rate, Q, Qd) + ca.jtimes(expr, Q, Qdd)


def _elements(ctx, layout: KernelLayout, d, q_own, lam):
    """(potential, Lagrangian, rows of the other elements' own variables, their equalities)."""
    s = ctx.structure
    potential = load_potential(ctx, d)
    lagrangian = potential
    own_rows, equalities = [], [ca.SX(0)] * layout.n_lam
    k = 0
    for element, _, n_own, lam_offset in layout.other_elements:
        t = s.elements[element]
        terms = FAMILIES.of(t).energy_terms(ctx, t, d)
        if n_own:
            mine = q_own[k : k + n_own]
            terms_energy = ca.substitute(terms.energy, terms.variables, mine)
            eq = [ca.substitute(g, terms.variables, mine) for _, g in terms.equalities]
            k += n_own
        else:
            terms_energy, eq = terms.energy, [g for _, g in terms.equalities]
        potential = potential + terms_energy
        element_lag = terms_energy + sum((lam[lam_offset + j] * g for j, g in enumerate(eq)), ca.SX(0))
        lagrangian = lagrangian + element_lag
        if n_own:
            own_rows.append(ca.gradient(element_lag, q_own[k - n_own : k]))
        for j, g in enumerate(eq):
            equalities[lam_offset + j] = g
    return potential, lagrangian, ca.vertcat(*own_rows) if own_rows else ca.SX(0, 1), equalities


def _start_point(ctx, t, d):
    """The link's start on its start body, for displacements d."""
    _, start_point, _ = t.geometry.build(ctx, t)
    i = t.start_body
    return ctx.place(i, ctx.body_axes(i, start_point), d)


def _end(ctx, chain, d, lam):
    """(where the link's end must be: target x, y (and its body's angle, clamped), the end's
    terms of the Lagrangian)."""
    t = chain.topology
    signature = chain.signature
    data = link_data(ctx, t, signature)
    _, start_point, _ = t.geometry.build(ctx, t)
    o = sum(size for name, size in data_layout(signature) if name != "undeformed_increment")
    end_point = start_point + ca.sum2(data[o : o + 2, :])
    j = t.end_body
    target = ctx.place(j, ctx.body_axes(j, end_point), d)
    m = chain.multiplier_offset
    wanted = [target[0], target[1]]
    term = -lam[m] * target[0] - lam[m + 1] * target[1]
    if t.end == "clamped":
        wanted.append(d[j][2])
        term = term - lam[m + 2] * d[j][2]
    return wanted, term


def _body_values(ctx, moving, X, V, A, pdot, pddot):
    """Every body coordinate's value, rate and acceleration: free ones from X, V, A; moving
    prescribed ones from p and its rates; others from p (rates zero)."""
    s = ctx.structure
    free = {bc: k for k, bc in enumerate(s.free)}
    values, rates, accelerations = [], [], []
    motion = {index: k for k, index in enumerate(moving)}
    for b, row in enumerate(s.prescribed):
        for c in range(3):
            if row[c] is None:
                k = free[(b, c)]
                values.append(X[k])
                rates.append(V[k])
                accelerations.append(A[k])
            elif row[c] == "":
                values += [ca.SX(0)]
                rates += [ca.SX(0)]
                accelerations += [ca.SX(0)]
            else:
                index = s.index[row[c]]
                values.append(ctx.p[index])
                k = motion.get(index)
                rates.append(pdot[k] if k is not None else ca.SX(0))
                accelerations.append(pddot[k] if k is not None else ca.SX(0))
    return ca.vertcat(*values), ca.vertcat(*rates), ca.vertcat(*accelerations)


def start_nodes(layout: KernelLayout, moving: tuple[int, ...]) -> ca.Function:
    """(uG, affine, k, p, pdot, pddot) -> (6 x chains): every chain's node 0 (its start on its
    start body): rho = position / k_rho, velocity, acceleration, from the body's coordinates."""
    s = layout.structure
    ctx = AssemblyContext(s)
    n_b, n_xg = len(s.bodies), len(layout.x_global)
    uG, affine, k = ca.SX.sym("uG", layout.n_global), ca.SX.sym("affine", n_xg, 3), ca.SX.sym("k", 4)
    pdot, pddot, p = ca.SX.sym("pdot", len(moving)), ca.SX.sym("pddot", len(moving)), ctx.p
    u_x = uG[:n_xg]
    X, V, A = affine[:, 0] + k[0] * u_x, affine[:, 1] + k[1] * u_x, affine[:, 2] + k[2] * u_x
    D, Dd, Ddd = (ca.SX.sym(name, 3 * n_b) for name in ("D", "Dd", "Ddd"))
    d = [D[3 * b : 3 * b + 3] for b in range(n_b)]
    nodes = []
    for chain in layout.chains:
        start = _start_point(ctx, chain.topology, d)
        rate = ca.jtimes(start, D, Dd)
        nodes.append(ca.vertcat(start / k[3], rate, ca.jtimes(rate, D, Dd) + ca.jtimes(start, D, Ddd)))
    values, rates, accelerations = _body_values(ctx, moving, X, V, A, pdot, pddot)
    out = ca.substitute(
        ca.horzcat(*nodes) if nodes else ca.SX(6, 0), ca.vertcat(D, Dd, Ddd), ca.vertcat(values, rates, accelerations)
    )
    fn = ca.Function(
        "start_nodes",
        [uG, affine, k, p, pdot, pddot],
        [out],
        ["uG", "affine", "k", "p", "pdot", "pddot"],
        ["nodes"],
        {"cse": True},
    )
    if fn.has_free():
        raise RuntimeError(f"start nodes have free symbols {fn.get_free()}")
    return fn
