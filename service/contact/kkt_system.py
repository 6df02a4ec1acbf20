"""The contact problem's active-set KKT system with friction (service.contact.problem states
it), as CasADi Functions: its residual and Jacobian, its p-Jacobian, and the sites' slides
relative to the objects from the reference state."""

from __future__ import annotations

import casadi as ca

from flexmech.models.graph.planar import rot
from flexmech.service.contact.wrenches import friction_force


def kkt_functions(V, g_eq, h_in, constraints, x, a, p, n_pairs: int, n_objects: int):
    """The active-set KKT system with friction (slipping rows: phi = mu sigma; sticking pairs:
    their tangential force tau and the condition that the contact does not slide relative to
    the object over the step from the reference state), its p-Jacobian, and the slides."""
    w = ca.vertcat(x, a)
    n_w, n_eq, n_in, n_a = w.numel(), g_eq.numel(), h_in.numel(), a.numel()
    n_rows = len(constraints.rows)
    n_element = n_in - n_rows
    lam_eq, lam_in, tau = ca.SX.sym("lam_eq", n_eq), ca.SX.sym("lam_in", n_in), ca.SX.sym("tau", n_pairs)
    active, phi = ca.SX.sym("active", n_in), ca.SX.sym("phi", n_in)
    freeze, ref = ca.SX.sym("freeze", n_a), ca.SX.sym("ref", n_a)
    stick, weights = ca.SX.sym("stick", n_pairs), ca.SX.sym("weights", n_rows)
    points_old = ca.SX.sym("points_old", 2, n_rows)
    origins_old, angles_old = ca.SX.sym("origins_old", 2, n_objects), ca.SX.sym("angles_old", n_objects)
    lagrangian = V + ca.dot(lam_eq, g_eq) - ca.dot(lam_in, h_in)
    stationarity = ca.gradient(lagrangian, w)
    slides, pair_slide, friction = _slides_and_friction(
        constraints, w, n_element, lam_in, phi, stick, weights, tau, points_old, origins_old, angles_old
    )
    stationarity = stationarity - friction
    if n_a:
        held = ca.vertcat(ca.SX.zeros(n_w - n_a), freeze)
        target = ca.vertcat(ca.SX.zeros(n_w - n_a), a - ref)
        stationarity = (1 - held) * stationarity + held * target
    complementarity = active * h_in + (1 - active) * lam_in
    sticking = ca.vertcat(*[stick[j] * pair_slide[j] + (1 - stick[j]) * tau[j] for j in range(n_pairs)])
    v = ca.vertcat(w, lam_eq, lam_in, tau)
    F = ca.vertcat(stationarity, g_eq, complementarity, sticking)
    inputs = [v, p, active, phi, freeze, ref, stick, weights, points_old, origins_old, angles_old]
    names = ["v", "p", "active", "phi", "freeze", "ref", "stick", "weights", "points_old", "origins_old", "angles_old"]
    kkt = ca.Function("contact_kkt", inputs, [F, ca.jacobian(F, v)], names, ["F", "J"])
    # phi (= mu sigma at a slipping row) is an input: its Jacobian carries a friction coefficient's
    # derivative (service.contact.sensitivity), which dF/dp alone would miss
    kkt_p = ca.Function("contact_kkt_p", inputs, [ca.jacobian(F, p), ca.jacobian(F, phi)], names, ["Fp", "Fphi"])
    slide_values = ca.vertcat(*slides) if slides else ca.SX(0, 1)
    slide_fn = ca.Function(
        "contact_slides",
        [w, p, points_old, origins_old, angles_old],
        [slide_values, ca.jacobian(slide_values, w), ca.jacobian(slide_values, p)],
        ["w", "p", "points_old", "origins_old", "angles_old"],
        ["slides", "slides_w", "slides_p"],
    )
    return kkt, kkt_p, slide_fn


def _slides_and_friction(
    constraints, w, n_element, lam_in, phi, stick, weights, tau, points_old, origins_old, angles_old
):
    """Per contact row, the site's tangential slide relative to the object from the reference
    state (0 at an object row); per pair, its rows' slides weighted by their shares of its
    normal force; and the friction forces at the pushing rows' material points, taken to the
    unknowns w."""
    n_pairs = tau.numel()
    slides = []
    pair_slide = [ca.SX(0) for _ in range(n_pairs)]
    points, forces = [], []  # the friction force at each pushing row's material point
    for k, row in enumerate(constraints.rows):
        if row.point is None:
            slides.append(ca.SX(0))
            continue
        unit_tangent = ca.vertcat(-row.normal[1], row.normal[0]) / ca.norm_2(row.normal)
        obj = constraints.pair_objects[row.pair]
        frame = constraints.object_frames[obj]
        carried = origins_old[:, obj] + rot(angles_old[obj] - frame.angle) @ (row.point - frame.origin)
        slide = ca.dot(unit_tangent, carried - points_old[:, k])  # the site's slide relative to the object
        slides.append(slide)
        pair_slide[row.pair] = pair_slide[row.pair] + weights[k] * slide
        points.append(row.point)
        forces.append(
            friction_force(row, lam_in[n_element + k], phi[n_element + k], stick[row.pair], weights[k], tau[row.pair])
        )
    friction = ca.SX.zeros(w.numel())
    if points:  # one Jacobian of every point: its transpose takes the forces to the unknowns
        friction = ca.mtimes(ca.jacobian(ca.vertcat(*points), w).T, ca.vertcat(*forces))
    return slides, pair_slide, friction
