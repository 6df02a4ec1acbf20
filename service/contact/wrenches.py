"""The contact forces' share of the reactions and of the links' start wrenches.

The structure's outputs come from its residual form, which knows no contact: a body's
reaction is what it holds of its elements, and a link's start wrench is its own energy's
derivative. Contact forces on a jaw carried by a body, or on a link's surface (whose points
move with the link's start body), are generalized forces on the bodies too: with every
body's displacement nudged by a symbol, the contact rows' derivative gives them,

    C_b = -(dh/d nudge_b)^T lam - (dP/d nudge_b)^T f_friction,

the wrench [Fx, Fy, M about b's reference point] that contact adds to what body b must
supply (the same sign as a reaction). A link's start wrench gains the part carried by its
own points."""

from __future__ import annotations

import casadi as ca

from flexmech.models.graph.planar import cross

REACTION_QUANTITIES = ("Fx", "Fy", "M")


def friction_force(row, lam, phi, stick, weight, tau) -> ca.SX:
    """The friction force on the site at a pushing row's point: phi (mu sigma) times its
    normal force when slipping, its share of tau when sticking, along the unit tangent (the
    normal turned by +90 deg)."""
    size = ca.norm_2(row.normal)
    unit_tangent = ca.vertcat(-row.normal[1], row.normal[0]) / size
    return (phi * lam * size + stick * weight * tau) * unit_tangent


def contact_wrenches(structure, nudged, nudge: ca.SX, w: ca.SX, p: ca.SX, n_eq: int, n_element: int, n_pairs: int):
    """builder(v, p, phi, stick, weights) -> (C: 3 x bodies, {link: C of the rows it carries, at
    its start body}) for the KKT state v = [w; lam_eq; lam_in; tau]."""
    rows = nudged.rows
    n_rows, n_bodies = len(rows), len(structure.bodies)
    lam, tau = ca.SX.sym("lam", n_rows), ca.SX.sym("tau", n_pairs)
    phi, stick, weights = ca.SX.sym("phi", n_rows), ca.SX.sym("stick", n_pairs), ca.SX.sym("weights", n_rows)
    links = sorted({row.carrier for row in rows if row.carrier is not None})

    def wrench(selected: list[int]) -> ca.SX:
        if not selected:
            return ca.SX.zeros(3 * n_bodies)
        h = ca.vertcat(*[rows[k].value for k in selected])
        total = -ca.mtimes(ca.jacobian(h, nudge).T, lam[selected])
        pushing = [k for k in selected if rows[k].point is not None]
        if pushing:
            points = ca.vertcat(*[rows[k].point for k in pushing])
            forces = ca.vertcat(
                *[
                    friction_force(rows[k], lam[k], phi[k], stick[rows[k].pair], weights[k], tau[rows[k].pair])
                    for k in pushing
                ]
            )
            total = total - ca.mtimes(ca.jacobian(points, nudge).T, forces)
        return ca.substitute(total, nudge, ca.SX.zeros(nudge.shape))

    every = wrench(list(range(n_rows)))
    starts = [structure.elements[[t.name for t in structure.elements].index(link)].start_body for link in links]
    carried = [
        wrench([k for k, row in enumerate(rows) if row.carrier == link])[3 * b : 3 * b + 3]
        for link, b in zip(links, starts)
    ]
    function = ca.Function(
        "contact_wrenches",
        [w, p, lam, tau, phi, stick, weights],
        [ca.reshape(every, 3, n_bodies), ca.horzcat(*carried) if carried else ca.SX(3, 0)],
    )
    n_w = w.numel()

    def builder(v, p_value, phi_all, stick_value, weights_value):
        lam_rows = v[n_w + n_eq + n_element : n_w + n_eq + n_element + n_rows]
        tau_value = v[n_w + n_eq + n_element + n_rows :]
        C, per_link = function(v[:n_w], p_value, lam_rows, tau_value, phi_all[n_element:], stick_value, weights_value)
        return C, dict(zip(links, [per_link[:, j] for j in range(len(links))]))

    return builder


def with_contact_wrenches(structure, graphs, y: ca.SX, corrections) -> ca.SX:
    """The structure's outputs y with contact's share added to the reactions (every
    supported body's, and the document's reaction outputs) and to the start wrenches of the
    links that carry contact (h, v: the internal force at u = 0; M_start)."""
    C, per_link = corrections
    names = list(graphs.output_names)
    y = ca.SX(y)

    def add(name: str, value) -> None:
        if name in names:
            y[names.index(name)] = y[names.index(name)] + value

    for b, body in enumerate(structure.bodies):
        if any(v is not None for v in structure.prescribed[b]):
            for c, quantity in enumerate(REACTION_QUANTITIES):
                add(f"reactions.{body}.{quantity}", C[c, b])
    for name, b in structure.reactions:
        for c, quantity in enumerate(REACTION_QUANTITIES):
            add(f"{name}.{quantity}", C[c, b])
    for link, extra in per_link.items():
        t = next(t for t in structure.elements if t.name == link)
        base, body = f"elements.{link}", structure.bodies[t.start_body]
        start = ca.vertcat(y[names.index(f"{base}.x_start")], y[names.index(f"{base}.y_start")])
        at = ca.vertcat(y[names.index(f"bodies.{body}.x")], y[names.index(f"bodies.{body}.y")])
        add(f"{base}.h", -extra[0])
        add(f"{base}.v", -extra[1])
        add(f"{base}.M_start", -(extra[2] - cross(start - at, extra[:2])))
    return y
