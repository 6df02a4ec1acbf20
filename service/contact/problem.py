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

from flexmech.models.contact.constraints import ContactGeometry, contact_constraints, substituted
from flexmech.models.contact.laws import FRICTION_LAWS, NORMAL_LAWS, check_law
from flexmech.models.errors import MechanismError
from flexmech.models.graph.assembly import graphs_for
from flexmech.models.graph.forms import symbolic_energy
from flexmech.models.graph.structure import Structure
from flexmech.service.contact.kkt_system import kkt_functions
from flexmech.service.contact.outputs import PAIR_OUTPUTS
from flexmech.service.contact.wrenches import contact_wrenches, friction_force, with_contact_wrenches


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
    nlp: dict  # {x, p, f, g} (SX), for service.solvers.ipopt
    axes_guess: ca.Function  # (x, p) -> a
    element_inequalities: ca.Function  # (x, p) -> h_el
    rows: ca.Function  # (w, p) -> h, normals (2 x rows), points (2 x rows), along
    frames: ca.Function  # (w, p) -> origins (2 x objects), angles
    kkt: ca.Function  # (v = [w; lam_eq; lam_in; tau], p, mode...) -> F, dF/dv (see service.contact.kkt_system)
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
        z[list(self.x_in_state)] = w[: self.n_x]
        z[list(self.multipliers_in_state)] = lam_eq
        return z


@lru_cache(maxsize=16)
def contact_problem(structure: Structure) -> ContactProblem:
    _check_pairs(structure)
    energy = symbolic_energy(structure, nudged=True)
    nudge = ca.vec(energy.nudge)
    geometry = ContactGeometry(energy.ctx, energy.d, energy.surfaces, structure.contacts)
    nudged = contact_constraints(geometry)  # every expression also of the bodies' nudges (for reactions)
    constraints = substituted(nudged, nudge, ca.SX.zeros(nudge.shape))
    x, a, p = energy.x, constraints.axes, energy.ctx.p
    w = ca.vertcat(x, a)
    _keep_moving_rows(constraints, nudged, w)
    n_rows = len(constraints.rows)
    nlp, potential, g_eq, h_el, h = _nlp(energy, constraints, nudge, w, p)
    rows = _rows_function(constraints, w, p, h)
    frames = _frames_function(constraints, w, p)
    axes_guess = ca.Function("axes_guess", [x, p], [constraints.axes_guess], ["x", "p"], ["a"])
    n_pairs, n_objects = len(structure.contacts.pairs), len(structure.contacts.objects)
    kkt, kkt_p, slides = kkt_functions(potential, g_eq, ca.vertcat(h_el, h), constraints, x, a, p, n_pairs, n_objects)
    results = pair_results(constraints, w, p, g_eq.numel(), h_el.numel(), n_pairs)
    corrections = contact_wrenches(structure, nudged, nudge, w, p, g_eq.numel(), h_el.numel(), n_pairs)
    outputs, names, kinds = _outputs(
        structure, energy, results, corrections, w, p, g_eq.numel(), h_el.numel() + n_rows, n_pairs
    )
    problem = ContactProblem(
        structure,
        x.numel(),
        a.numel(),
        g_eq.numel(),
        h_el.numel() + n_rows,
        h_el.numel(),
        tuple(row.pair for row in constraints.rows),
        tuple(row.point is not None for row in constraints.rows),
        tuple(row.axis for row in constraints.rows),
        tuple(constraints.axis_pairs),
        tuple(energy.x_in_state),
        tuple(energy.multipliers_in_state),
        nlp,
        axes_guess,
        ca.Function("element_inequalities", [x, p], [h_el], ["x", "p"], ["h"]),
        rows,
        frames,
        kkt,
        kkt_p,
        slides,
        results,
        p.numel(),
        n_pairs,
        tuple(pair.object for pair in structure.contacts.pairs),
        outputs,
        names,
        kinds,
        _jacobians(outputs),
        *_drawing(energy, geometry, w, p, nudge),
    )
    _check_no_free_symbols(rows, frames, axes_guess, kkt, slides, results)
    return problem


def _check_pairs(structure: Structure) -> None:
    """At least one contact pair, and every pair's laws known."""
    if structure.contacts is None or not structure.contacts.pairs:
        raise MechanismError("/contacts/pairs", "the contact analysis needs at least one contact pair")
    for pair in structure.contacts.pairs:
        check_law(NORMAL_LAWS, "normal", pair.normal_law, "contact", f"{pair.pointer}/normal/law")
        check_law(FRICTION_LAWS, "friction", pair.friction_law, "contact", f"{pair.pointer}/friction/law")


def _keep_moving_rows(constraints, nudged, w: ca.SX) -> None:
    """A row no unknown moves (a surface point at a clamp on a fixed body) cannot change: left
    out, of both forms of the constraints."""
    kept = [k for k, row in enumerate(constraints.rows) if ca.depends_on(row.value, w)]
    constraints.rows = [constraints.rows[k] for k in kept]
    nudged.rows = [nudged.rows[k] for k in kept]


def _unnudged(expression: ca.SX, nudge: ca.SX) -> ca.SX:
    """The expression with the bodies' nudges at 0."""
    return ca.substitute(expression, nudge, ca.SX.zeros(nudge.shape))


def _nlp(energy, constraints, nudge: ca.SX, w: ca.SX, p: ca.SX):
    """The NLP {x, p, f, g} (module docstring), the contact rows relaxed by a shift each; with
    its parts V, g_eq, h_el and the contact rows' h."""
    shift = ca.SX.sym("shift", len(constraints.rows))
    g_eq = _unnudged(_stack([g for _, g in energy.equalities]), nudge)
    h_el = _unnudged(_stack([h for _, h in energy.inequalities]), nudge)
    potential = _unnudged(energy.potential, nudge)
    h = _stack([row.value for row in constraints.rows])
    nlp = {"x": w, "p": ca.vertcat(p, shift), "f": potential, "g": ca.vertcat(g_eq, h_el, h + shift)}
    return nlp, potential, g_eq, h_el, h


def _rows_function(constraints, w: ca.SX, p: ca.SX, h: ca.SX) -> ca.Function:
    """Per contact row at a state: its gap h, normal, site point and site parameter."""
    zero2 = ca.SX.zeros(2)
    normals = ca.horzcat(*[row.normal if row.normal is not None else zero2 for row in constraints.rows])
    points = ca.horzcat(*[row.point if row.point is not None else zero2 for row in constraints.rows])
    along = _stack([row.site_parameter if row.site_parameter is not None else ca.SX(0) for row in constraints.rows])
    return ca.Function(
        "contact_rows", [w, p], [h, normals, points, along], ["w", "p"], ["h", "normals", "points", "along"]
    )


def _frames_function(constraints, w: ca.SX, p: ca.SX) -> ca.Function:
    """Every object's frame at a state: its origin and angle."""
    return ca.Function(
        "object_frames",
        [w, p],
        [
            ca.horzcat(*[f.origin for f in constraints.object_frames]),
            _stack([f.angle for f in constraints.object_frames]),
        ],
        ["w", "p"],
        ["origins", "angles"],
    )


def _check_no_free_symbols(*functions: ca.Function) -> None:
    for fn in functions:
        if fn.has_free():
            raise RuntimeError(f"graph {fn.name()} has free symbols {fn.get_free()}")


def _stack(items: list) -> ca.SX:
    return ca.vertcat(*items) if items else ca.SX(0, 1)


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
    phi, stick, weights = (
        ca.SX.sym("phi", n_element + n_rows),
        ca.SX.sym("stick", n_pairs),
        ca.SX.sym("weights", n_rows),
    )
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
        friction_sum[j] = friction_sum[j] + friction_force(
            row, lam[n_element + k], phi[n_element + k], stick[j], weights[k], tau[j]
        )
        magnitude[j] = magnitude[j] + pushing
        point[j] = point[j] + pushing * row.point
        along[j] = along[j] + pushing * row.site_parameter
    tiny = 1e-300
    normal_force = [_length(n) for n in normal_sum]
    tangential = [ca.dot(f, ca.vertcat(-n[1], n[0])) / (_length(n) + tiny) for f, n in zip(friction_sum, normal_sum)]
    v = ca.vertcat(w, lam_eq, lam, tau)
    outputs = [
        ca.horzcat(*[n + f for n, f in zip(normal_sum, friction_sum)]),
        ca.vertcat(*normal_force),
        ca.vertcat(*tangential),
        ca.horzcat(*[q / (m + tiny) for q, m in zip(point, magnitude)]),
        ca.vertcat(*[s / (m + tiny) for s, m in zip(along, magnitude)]),
        ca.horzcat(*[n / (_length(n) + tiny) for n in normal_sum]),
    ]
    return ca.Function(
        "pair_results",
        [v, p, phi, stick, weights],
        outputs,
        ["v", "p", "phi", "stick", "weights"],
        ["force", "normal_force", "tangential_force", "point", "along", "normal"],
    )


def _length(vector: ca.SX) -> ca.SX:
    """|vector|, 0 at 0 with a derivative there (0, not norm_2's 0/0: an open pair's forces do
    not change)."""
    square = ca.dot(vector, vector)
    return ca.if_else(square > 0, ca.sqrt(ca.fmax(square, 1e-300)), 0.0)


def _outputs(structure, energy, results, corrections, w, p, n_eq, n_in, n_pairs):
    """y(v, p, mode): "contacts.<pair>.<quantity>" of every pair (PAIR_OUTPUTS), then the
    structure's own outputs at the state (its residual-form z assembled from v), its
    reactions and its links' start wrenches with the contact forces they carry added."""
    names = [f"contacts.{pair.name}.{q}" for pair in structure.contacts.pairs for q, _ in PAIR_OUTPUTS]
    kinds = [kind for _ in structure.contacts.pairs for _, kind in PAIR_OUTPUTS]
    v = ca.SX.sym("v", w.numel() + n_eq + n_in + n_pairs)
    phi, stick, weights = ca.SX.sym("phi", n_in), ca.SX.sym("stick", n_pairs), ca.SX.sym("weights", results.size1_in(4))
    force, normal, tangential, point, along, _ = results(v, p, phi, stick, weights)
    per_pair = [
        ca.vertcat(force[0, j], force[1, j], normal[j], tangential[j], point[0, j], point[1, j], along[j])
        for j in range(n_pairs)
    ]
    z = ca.SX.zeros(len(energy.x_in_state) + len(energy.multipliers_in_state))
    for k, slot in enumerate(energy.x_in_state):
        z[slot] = v[k]
    for k, slot in enumerate(energy.multipliers_in_state):
        z[slot] = v[w.numel() + k]
    graphs = graphs_for(structure)
    y_structure = with_contact_wrenches(structure, graphs, graphs.outputs(z, p), corrections(v, p, phi, stick, weights))
    y = ca.vertcat(*per_pair, y_structure)
    names += list(graphs.output_names)
    kinds += list(graphs.output_kinds)
    function = ca.Function(
        "contact_outputs", [v, p, phi, stick, weights], [y], ["v", "p", "phi", "stick", "weights"], ["y"]
    )
    return function, tuple(names), tuple(kinds)


def _jacobians(outputs: ca.Function) -> ca.Function:
    args = [ca.SX.sym(outputs.name_in(i), outputs.sparsity_in(i)) for i in range(outputs.n_in())]
    y = outputs(*args)
    return ca.Function(
        "contact_outputs_jacobian",
        args,
        [ca.jacobian(y, args[0]), ca.jacobian(y, args[1]), ca.jacobian(y, args[2])],
        [outputs.name_in(i) for i in range(outputs.n_in())],
        ["y_v", "y_p", "y_phi"],
    )


def _drawing(energy, geometry, w, p, nudge):
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
    function = ca.Function(
        "contact_drawing",
        [w, p],
        [
            _unnudged(ca.horzcat(*vertices), nudge) if vertices else ca.SX(2, 0),
            _unnudged(ca.horzcat(*outline), nudge) if outline else ca.SX(2, 0),
        ],
        ["w", "p"],
        ["jaws", "links"],
    )
    return function, tuple(links), tuple(jaws)
