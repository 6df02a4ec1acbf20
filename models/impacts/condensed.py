"""Elements with unknowns of their own (a link, by shooting or by elements; an exact curved
beam) in an impact model: a massless flexure of constant stiffness, the element's own statics
tangent about the drawn (unloaded) state, condensed onto its end body.

The statics of the element alone, its `from` body held as drawn and its `to` body free, has
the tangent K_T(z, p) of the residual form (models.graph.assembly); at the undeformed state z = 0
the inverse of its compliance (the free body's motion under unit loads on it) is the 3 x 3
stiffness K of that body's reference point (global axes, SI), moved to the element's end E.
The impact model then writes the flexure as the curved beams' closed form does (seed 000,
Eq. 2): energy 1/2 psi.K.psi with psi the motion of the end body's point at E relative to the
start body's point there, in the start body's axes; with the `turning` stiffness K turns with
the end body (seed 004, Eq. 8). So at small deflection the impact run agrees with the
element's statics to first order; large deflection of the element is not modelled (as for
the curved beams' constant-stiffness models), and neither is its mass.

K is a computed block of the book (models.impacts.book): a CasADi Function of the element's
numbers, evaluated once per run and differentiated exactly, so sensitivities and studies see
every field of the element."""

from __future__ import annotations

import casadi as ca
import numpy as np

from flexmech.models.errors import MechanismError
from flexmech.models.graph.planar import rot
from flexmech.models.impacts.coordinates import NOT_SECTIONS, BodyCoordinates, parameters_of

UNDEFORMED_TOLERANCE = 1e-10  # the residual at z = 0 (nondimensional): the element is unloaded as drawn


def condensed_flexure(rb: BodyCoordinates, name: str) -> tuple[ca.SX, ca.SX, ca.SX]:
    """(1/2 psi.K.psi, psi, K) of element `name`, as an impact_flexure hook gives them."""
    from flexmech.models.graph.mechanism import compile_mechanism

    doc, base = rb.book.document, f"/elements/{name}"
    element = doc.elements[name]
    i, j = rb.body(element.from_, f"{base}/from"), rb.body(element.to, f"{base}/to")
    alone = doc.model_copy(
        update={
            **NOT_SECTIONS,
            "elements": {name: element},
            "gravity": None,
            "bodies": {
                element.from_: doc.bodies[element.from_].model_copy(update={"fixed": True}),
                element.to: doc.bodies[element.to].model_copy(update={"fixed": False}),
            },
        }
    )
    mech = compile_mechanism(alone)
    free = mech.structure.free
    if len(free) != 3:
        raise MechanismError(
            f"{base}/to",
            f"body '{element.to}' is not free in the element's own statics: an "
            "impact simulation condenses the element onto its end body",
        )
    _check_unloaded(mech, base)
    numbers = parameters_of(rb, mech, scaled=False)
    stiffness, end = _stiffness_function(mech, name)
    _check_holds(stiffness, mech, base, element.to)
    K, E = rb.book.computed(stiffness, numbers, f"K_{name}"), rb.book.computed(end, numbers, f"end_{name}")
    # psi at the element's end E (drawn): relative to the start body's material point there
    relative = rot(-rb.rotation(i)) @ (rb.drawn_point(j, E) - rb.drawn_point(i, E))
    psi = ca.vertcat(relative, rb.rotation(j) - rb.rotation(i))
    return 0.5 * ca.dot(psi, K @ psi), psi, K


def _check_unloaded(mech, base: str) -> None:
    residual = np.asarray(mech.graphs.residual(np.zeros(mech.n_free), mech.p())).ravel()
    if np.abs(residual).max() > UNDEFORMED_TOLERANCE:
        raise MechanismError(
            f"{base}/type",
            "this element is loaded in its drawn state (its undeformed unknowns "
            "are not an equilibrium), and impact simulations take it by its stiffness about that "
            "state",
        )


def _check_holds(stiffness: ca.Function, mech, base: str, body: str) -> None:
    try:
        K = np.asarray(stiffness(mech.si_values))
    except RuntimeError:  # a singular solve: some motion of the end body meets no stiffness
        K = np.full((3, 3), np.nan)
    if not np.all(np.isfinite(K)) or np.linalg.cond(K) > 1e12:
        raise MechanismError(
            f"{base}/type",
            f"the element's stiffness at body '{body}' is not finite and positive "
            "in every direction, and an impact simulation takes an element by that stiffness: an "
            'inextensible straight link is rigid along itself (give it "axial": true), a pinned '
            "end leaves its body free to turn (clamp it)",
        )


def _stiffness_function(mech, name: str) -> tuple[ca.Function, ca.Function]:
    """SI numbers of the element's statics parameters -> K (3 x 3, SI: N/m, N, N m/rad) at the
    element's end on its end body, and -> that end E (2, SI: the last point of its drawn centre
    line; the end body's reference point for an element that draws none)."""
    structure, scales = mech.structure, mech.scales
    numbers = ca.MX.sym("numbers", len(structure.parameters))
    p = numbers * ca.DM([1 / scales.of(parameter.kind) for parameter in structure.parameters])
    z = ca.MX.zeros(mech.n_free)
    _, tangent = mech.graphs.residual_and_tangent(z, p)
    # the end body's compliance: its motion under unit loads on it (the element's own rows
    # alone may be singular: an inextensible straight link's axial force moves no end at first order)
    unit_loads = ca.vertcat(ca.MX.eye(3), ca.MX.zeros(mech.n_free - 3, 3))
    compliance = ca.solve(ca.densify(tangent), unit_loads, "qr")[:3, :]
    body = ca.solve(compliance, ca.MX.eye(3), "qr")
    L, F = scales.length, scales.force
    at_reference = ca.diag(ca.DM([F, F, F * L])) @ body @ ca.diag(ca.DM([1 / L, 1 / L, 1]))
    end_body = structure.free[0][0]
    reference = ca.vertcat(*[p[structure.index[f"/bodies/{structure.bodies[end_body]}/position/{k}"]] for k in (0, 1)])
    end = reference
    for element, first, columns, start, finish in mech.graphs.shape_segments:
        if element == name and end_body in (start, finish):
            _, undeformed = mech.graphs.shapes(z, p)
            end = undeformed[:, first + columns - 1 if finish == end_body else first]
    arm = (end - reference) * L  # from the end body's reference point to E
    # a motion (u_E, theta) at E is (u_E + theta (arm_y, -arm_x), theta) at the reference point
    to_reference = ca.MX.eye(3)
    to_reference[0, 2], to_reference[1, 2] = arm[1], -arm[0]
    K = to_reference.T @ at_reference @ to_reference
    return (ca.Function("condensed_stiffness", [numbers], [K]), ca.Function("condensed_end", [numbers], [end * L]))
