"""The contact problem of a structure, as CasADi Functions built once per structure.

Unknowns w = [x; a]: the energy form's x (free body coordinates, the links' variables) and
the separating axes a. Parameters: the mechanism's p, and a shift s per contact row (the
approach from a penetrating start relaxes h >= 0 to h + s >= 0 and lets s fall to 0).

    NLP:  minimize V(x, p)  s.t.  g(x, p) = 0,  h_el(x, p) >= 0,  h(w, p) + s >= 0

The active-set KKT system (for friction and for sensitivities) in v = [w; lam_eq; lam_in; tau]:

    grad_w V + J_eq^T lam_eq - J_in^T lam_in - Q_friction = 0     (rows of frozen axes: a - a_ref = 0)
    g = 0
    active: h = 0,  inactive: lam = 0
    sticking pair j: its slide over the step = 0,  otherwise tau_j = 0

with Q_friction = sum_k (dP_k/dw)^T f_k t_k: at a slipping row f_k = phi_k (= mu sigma) times
the row's normal force, at a sticking pair's rows f_k = weight_k tau_j, t_k the unit tangent,
acting at the site's material point P_k. A row's slide is the tangential motion of the
site's material point relative to the object's material point at the contact, from the
reference (previous) state: the object's point is carried back by the object's rigid motion.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from models.assembly import graphs_for
from models.contact.constraints import ContactGeometry, contact_constraints, substituted
from models.contact.laws import FRICTION_LAWS, NORMAL_LAWS, check_law
from models.errors import MechanismError
from models.forms import symbolic_energy
from models.planar import rot
from models.structure import Structure
from service.contact.outputs import PAIR_OUTPUTS
from service.contact.wrenches import contact_wrenches, friction_force, with_contact_wrenches


@dataclass(frozen=True)
class ContactProblem:
    structure: Structure
    n_x: int
    n_axes: int
    n_eq: int
    n_in: int  # inequality rows: the elements' own, then the contact rows
    n_element_in: int
    row_pairs: tuple[int, ...]  # per contact row, its pair
    row_pushes: tuple[bool, ...]  # per contact row, whether it pushes a site point
    row_axes: tuple[int, ...]  # per contact row, its separating axis (-1: pointwise)
    axis_pairs: tuple[int, ...]
    x_in_state: tuple[int, ...]
    multipliers_in_state: tuple[int, ...]
    nlp: dict  # {x, p, f, g} (SX), for service.ipopt
    axes_guess: ca.Function  # (x, p) -> a
    element_inequalities: ca.Function  # (x, p) -> h_el
    rows: ca.Function  # (w, p) -> h, normals (2 x rows), points (2 x rows), along
    frames: ca.Function  # (w, p) -> origins (2 x objects), angles
    kkt: ca.Function  # (v = [w; lam_eq; lam_in; tau], p, mode...) -> F, dF/dv (see _kkt_functions)
    kkt_parameters: ca.Function  # the same inputs -> dF/dp, dF/dphi
    slides: ca.Function  # (w, p, points_old, origins_old, angles_old) -> per row, the site's tangential slide,
    #                      and its w- and p-Jacobians
    pair_results: ca.Function  # (v, p, phi, stick, weights) -> per pair: force on the site, normal and
    #                            tangential force, contact point, site parameter (pair_results())
    n_p: int
    n_pairs: int
    pair_objects: tuple[int, ...]
    outputs: ca.Function  # (v, p, phi, stick, weights) -> y: every pair's results, then the structure's outputs
    output_names: tuple[str, ...]
    output_kinds: tuple[str, ...]
    outputs_jacobian: ca.Function  # the same inputs -> dy/dv, dy/dp
    drawing: ca.Function  # (w, p) -> jaw vertices (2 x all), link outlines (2 x 3 per point: centre, left, right)
    drawn_links: tuple[tuple[str, int], ...]  # (link, points) in the drawing's outline columns
    drawn_jaws: tuple[tuple[str, int, bool], ...]  # (site, vertices, closed)

    @property
    def n_w(self) -> int:
        return self.n_x + self.n_axes

    @property
    def n_rows(self) -> int:
        return self.n_in - self.n_element_in

    def to_state(self, w: np.ndarray, lam_eq: np.ndarray) -> np.ndarray:
        """The residual form's z (for the structure's outputs and reactions)."""
        z = np.zeros(len(self.x_in_state) + len(self.multipliers_in_state))
        z[list(self.x_in_state)] = w[:self.n_x]
        z[list(self.multipliers_in_state)] = lam_eq
        return z


@lru_cache(maxsize=16)
def contact_problem(structure: Structure) -> ContactProblem:
    if structure.contacts is None or not structure.contacts.pairs:
        raise MechanismError("/contacts/pairs", "the contact analysis needs at least one contact pair")
    for pair in structure.contacts.pairs:
        check_law(NORMAL_LAWS, "normal", pair.normal_law, "contact", f"{pair.pointer}/normal/law")
        check_law(FRICTION_LAWS, "friction", pair.friction_law, "contact", f"{pair.pointer}/friction/law")
    energy = symbolic_energy(structure, nudged=True)
    nudge = ca.vec(energy.nudge)
    geometry = ContactGeometry(energy.ctx, energy.d, energy.surfaces, structure.contacts)
    nudged = contact_constraints(geometry)  # every expression also of the bodies' nudges (for reactions)
    constraints = substituted(nudged, nudge, ca.SX.zeros(nudge.shape))
    x, a, p = energy.x, constraints.axes, energy.ctx.p
    w = ca.vertcat(x, a)
    # a row no unknown moves (a surface point at a clamp on a fixed body) cannot change: left out
    kept = [k for k, row in enumerate(constraints.rows) if ca.depends_on(row.value, w)]
    constraints.rows = [constraints.rows[k] for k in kept]
    nudged.rows = [nudged.rows[k] for k in kept]
    n_rows = len(constraints.rows)
    shift = ca.SX.sym("shift", n_rows)

    def unnudged(e):
        return ca.substitute(e, nudge, ca.SX.zeros(nudge.shape))

    g_eq = unnudged(_stack([g for _, g in energy.equalities]))
    h_el = unnudged(_stack([h for _, h in energy.inequalities]))
    potential = unnudged(energy.potential)
    h = _stack([row.value for row in constraints.rows])
    nlp = {"x": w, "p": ca.vertcat(p, shift), "f": potential, "g": ca.vertcat(g_eq, h_el, h + shift)}
    zero2 = ca.SX.zeros(2)
    normals = ca.horzcat(*[row.normal if row.normal is not None else zero2 for row in constraints.rows])
    points = ca.horzcat(*[row.point if row.point is not None else zero2 for row in constraints.rows])
    along = _stack([row.site_parameter if row.site_parameter is not None else ca.SX(0) for row in constraints.rows])
    rows = ca.Function("contact_rows", [w, p], [h, normals, points, along], ["w", "p"],
                       ["h", "normals", "points", "along"])
    frames = ca.Function("object_frames", [w, p], [ca.horzcat(*[f.origin for f in constraints.object_frames]),
                                                   _stack([f.angle for f in constraints.object_frames])],
                         ["w", "p"], ["origins", "angles"])
    axes_guess = ca.Function("axes_guess", [x, p], [constraints.axes_guess], ["x", "p"], ["a"])
    n_pairs, n_objects = len(structure.contacts.pairs), len(structure.contacts.objects)
    kkt, kkt_p, slides = _kkt_functions(potential, g_eq, ca.vertcat(h_el, h), constraints, x, a, p,
                                        n_pairs, n_objects)
    results = pair_results(constraints, w, p, g_eq.numel(), h_el.numel(), n_pairs)
    corrections = contact_wrenches(structure, nudged, nudge, w, p, g_eq.numel(), h_el.numel(), n_pairs)
    outputs, names, kinds = _outputs(structure, results, corrections, w, p, g_eq.numel(), h_el.numel() + n_rows,
                                     n_pairs, energy.x_in_state, energy.multipliers_in_state)
    problem = ContactProblem(structure, x.numel(), a.numel(), g_eq.numel(), h_el.numel() + n_rows, h_el.numel(),
                             tuple(row.pair for row in constraints.rows),
                             tuple(row.point is not None for row in constraints.rows),
                             tuple(row.axis for row in constraints.rows), tuple(constraints.axis_pairs),
                             tuple(energy.x_in_state), tuple(energy.multipliers_in_state), nlp, axes_guess,
                             ca.Function("element_inequalities", [x, p], [h_el], ["x", "p"], ["h"]), rows,
                             frames, kkt, kkt_p, slides, results, p.numel(), n_pairs,
                             tuple(pair.object for pair in structure.contacts.pairs), outputs, names, kinds,
                             _jacobians(outputs), *_drawing(energy, geometry, w, p, unnudged))
    for fn in (rows, frames, axes_guess, kkt, slides, results):
        if fn.has_free():
            raise RuntimeError(f"graph {fn.name()} has free symbols {fn.get_free()}")
    return problem


def _stack(items: list) -> ca.SX:
    return ca.vertcat(*items) if items else ca.SX(0, 1)


def _kkt_functions(V, g_eq, h_in, constraints, x, a, p, n_pairs: int, n_objects: int):
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
        forces.append(friction_force(row, lam_in[n_element + k], phi[n_element + k], stick[row.pair], weights[k],
                                     tau[row.pair]))
    friction = ca.SX.zeros(n_w)
    if points:  # one Jacobian of every point: its transpose takes the forces to the unknowns
        friction = ca.mtimes(ca.jacobian(ca.vertcat(*points), w).T, ca.vertcat(*forces))
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
    slide_values = _stack(slides)
    slide_fn = ca.Function("contact_slides", [w, p, points_old, origins_old, angles_old],
                           [slide_values, ca.jacobian(slide_values, w), ca.jacobian(slide_values, p)],
                           ["w", "p", "points_old", "origins_old", "angles_old"], ["slides", "slides_w", "slides_p"])
    return kkt, kkt_p, slide_fn



def pair_results(constraints, w: ca.SX, p: ca.SX, n_eq: int, n_element: int, n_pairs: int) -> ca.Function:
    """Per pair, from the state v = [w; lam_eq; lam_in; tau]: the force on the site (normal
    part lam dh/dP at each pushing row, plus friction), its normal and tangential components
    (the tangent turns the normal by +90 deg), the contact point and the site parameter
    (normal-force weighted means over the pair's rows), and the unit normal (away from the
    object)."""
    n_rows = len(constraints.rows)
    lam = ca.SX.sym("lam_in", n_element + n_rows)
    tau = ca.SX.sym("tau", n_pairs)
    lam_eq = ca.SX.sym("lam_eq", n_eq)
    phi, stick, weights = ca.SX.sym("phi", n_element + n_rows), ca.SX.sym("stick", n_pairs), ca.SX.sym("weights", n_rows)
    normal_sum = [ca.SX.zeros(2) for _ in range(n_pairs)]
    friction_sum = [ca.SX.zeros(2) for _ in range(n_pairs)]
    magnitude = [ca.SX(0) for _ in range(n_pairs)]
    point = [ca.SX.zeros(2) for _ in range(n_pairs)]
    along = [ca.SX(0) for _ in range(n_pairs)]
    for k, row in enumerate(constraints.rows):
        if row.point is None:
            continue
        j = row.pair
        pushing = lam[n_element + k] * ca.norm_2(row.normal)
        normal_sum[j] = normal_sum[j] + lam[n_element + k] * row.normal
        friction_sum[j] = friction_sum[j] + friction_force(row, lam[n_element + k], phi[n_element + k], stick[j],
                                                           weights[k], tau[j])
        magnitude[j] = magnitude[j] + pushing
        point[j] = point[j] + pushing * row.point
        along[j] = along[j] + pushing * row.site_parameter
    tiny = 1e-300
    normal_force = [_length(n) for n in normal_sum]
    tangential = [ca.dot(f, ca.vertcat(-n[1], n[0])) / (_length(n) + tiny) for f, n in zip(friction_sum, normal_sum)]
    v = ca.vertcat(w, lam_eq, lam, tau)
    outputs = [ca.horzcat(*[n + f for n, f in zip(normal_sum, friction_sum)]), ca.vertcat(*normal_force),
               ca.vertcat(*tangential), ca.horzcat(*[q / (m + tiny) for q, m in zip(point, magnitude)]),
               ca.vertcat(*[s / (m + tiny) for s, m in zip(along, magnitude)]),
               ca.horzcat(*[n / (_length(n) + tiny) for n in normal_sum])]
    return ca.Function("pair_results", [v, p, phi, stick, weights], outputs, ["v", "p", "phi", "stick", "weights"],
                       ["force", "normal_force", "tangential_force", "point", "along", "normal"])


def _length(vector: ca.SX) -> ca.SX:
    """|vector|, 0 at 0 with a derivative there (0, not norm_2's 0/0: an open pair's forces do
    not change)."""
    square = ca.dot(vector, vector)
    return ca.if_else(square > 0, ca.sqrt(ca.fmax(square, 1e-300)), 0.0)


def _outputs(structure, results, corrections, w, p, n_eq, n_in, n_pairs, x_in_state, multipliers_in_state):
    """y(v, p, mode): "contacts.<pair>.<quantity>" of every pair (PAIR_OUTPUTS), then the
    structure's own outputs at the state (its residual-form z assembled from v), its
    reactions and its links' start wrenches with the contact forces they carry added."""
    names = [f"contacts.{pair.name}.{q}" for pair in structure.contacts.pairs for q, _ in PAIR_OUTPUTS]
    kinds = [kind for _ in structure.contacts.pairs for _, kind in PAIR_OUTPUTS]
    v = ca.SX.sym("v", w.numel() + n_eq + n_in + n_pairs)
    phi, stick, weights = ca.SX.sym("phi", n_in), ca.SX.sym("stick", n_pairs), ca.SX.sym("weights", results.size1_in(4))
    force, normal, tangential, point, along, _ = results(v, p, phi, stick, weights)
    per_pair = [ca.vertcat(force[0, j], force[1, j], normal[j], tangential[j], point[0, j], point[1, j], along[j])
                for j in range(n_pairs)]
    z = ca.SX.zeros(len(x_in_state) + len(multipliers_in_state))
    for k, slot in enumerate(x_in_state):
        z[slot] = v[k]
    for k, slot in enumerate(multipliers_in_state):
        z[slot] = v[w.numel() + k]
    graphs = graphs_for(structure)
    y_structure = with_contact_wrenches(structure, graphs, graphs.outputs(z, p), corrections(v, p, phi, stick, weights))
    y = ca.vertcat(*per_pair, y_structure)
    names += list(graphs.output_names)
    kinds += list(graphs.output_kinds)
    function = ca.Function("contact_outputs", [v, p, phi, stick, weights], [y], ["v", "p", "phi", "stick", "weights"], ["y"])
    return function, tuple(names), tuple(kinds)


def _jacobians(outputs: ca.Function) -> ca.Function:
    args = [ca.SX.sym(outputs.name_in(i), outputs.sparsity_in(i)) for i in range(outputs.n_in())]
    y = outputs(*args)
    return ca.Function("contact_outputs_jacobian", args, [ca.jacobian(y, args[0]), ca.jacobian(y, args[1]),
                                                          ca.jacobian(y, args[2])],
                       [outputs.name_in(i) for i in range(outputs.n_in())], ["y_v", "y_p", "y_phi"])


def _drawing(energy, geometry, w, p, unnudged):
    """The sites drawn at a state: every jaw's vertices, every link's centre line and surfaces."""
    jaws, vertices = [], []
    for site in geometry.topology.sites:
        if site.type == "jaw":
            vertices += geometry.jaw_vertices(site)[0]
            jaws.append((site.name, site.n_vertices, site.closed))
    links, outline = [], []
    for name, surfaces in energy.surfaces.items():
        for point in surfaces.points:
            half = point.half_thickness if point.half_thickness is not None else ca.SX(0)
            outline += [point.centre, point.centre + half * point.normal, point.centre - half * point.normal]
        links.append((name, len(surfaces.points)))
    function = ca.Function("contact_drawing", [w, p], [unnudged(ca.horzcat(*vertices)) if vertices else ca.SX(2, 0),
                                                       unnudged(ca.horzcat(*outline)) if outline else ca.SX(2, 0)],
                           ["w", "p"], ["jaws", "links"])
    return function, tuple(links), tuple(jaws)
