"""Geometry-free oracles of the contact analysis (seed 002 Ch. 6; reading notes
seed-002-contact.md): a tip on a frictionless half-plane is Frisch-Fay's cantilever under
the normal tip force; a small indentation by a circle is linear beam theory, the ratio's
error falling as the indentation squared; a cantilever wrapped onto a cylinder by a large tip
force has the cylinder's curvature; a contact-free state is the shooting solution; the
contact force converges at the discretization's order."""

from __future__ import annotations

import numpy as np
import pytest
from elastica_oracles import cantilever_tip

from flexmech.models import compile_mechanism, load_document
from flexmech.service.analyses.base import AnalysisRequest
from flexmech.service.analyses.contact import CONTACT
from flexmech.service.contact.kkt import split
from flexmech.service.contact.problem import contact_problem
from flexmech.service.contact.solve import solve_state
from flexmech.service.solvers.equilibrium import NewtonOptions, solve_equilibrium

E, B, H, L = 2e11, 0.01, 0.001, 0.1
EI = E * B * H**3 / 12


def strip(
    intervals: int = 16,
    degree: int = 3,
    contacts: dict | None = None,
    loads: dict | None = None,
    discretization: str = "elements",
) -> dict:
    """A steel strip clamped at the origin along +x, its end a free body "tip"."""
    link = {
        "type": "link",
        "from": "ground",
        "to": "tip",
        "length": L,
        "material": "steel",
        "section": "strip",
        "discretization": discretization,
        "intervals": intervals,
    }
    link.update({"degree": degree} if discretization == "elements" else {"order": 12})
    doc = {
        "units": {"length": "m", "force": "N", "angle": "rad"},
        "materials": {"steel": {"E": E, "nu": 0.3}},
        "sections": {"strip": {"b": B, "h": H}},
        "bodies": {"ground": {"fixed": True, "position": [0, 0]}, "tip": {"position": [L, 0]}},
        "elements": {"L": link},
        "loads": loads or {},
    }
    if contacts is not None:
        doc["contacts"] = contacts
    return doc


def tip_point_against(obj: dict) -> dict:
    """The link's end point (a one-vertex jaw on the tip body) against one object."""
    return {
        "objects": {"obstacle": obj},
        "sites": {"tip_point": {"type": "jaw", "body": "tip", "vertices": [[0, 0]]}},
        "pairs": {"touch": {"site": "tip_point", "object": "obstacle"}},
    }


def contact_report(doc: dict) -> dict:
    report = CONTACT.run(compile_mechanism(load_document(doc)), AnalysisRequest())
    assert report["status"] == "converged", report["message"]
    return report


def test_a_tip_on_a_frictionless_half_plane_is_frisch_fays_cantilever():
    """The plane y = -0.4 L pushes the tip down (the solid above it, the tip starting inside
    and approached from outside): the contact force is vertical and the tip sits where
    Frisch-Fay's elastica under that force puts it, to 1e-8 of L."""
    depth = 0.4 * L
    report = contact_report(
        strip(contacts=tip_point_against({"type": "half_plane", "point": [0, -depth], "normal": [0, -1]}))
    )
    pair = report["pairs"]["touch"]
    force = -pair["force"][1]  # downward on the tip
    assert abs(pair["force"][0]) < 1e-9 * force
    x, y, _ = cantilever_tip(EI, L, force)  # Frisch-Fay, upward force: mirror it
    tip = np.array([report["outputs"]["elements.L.x_end"], report["outputs"]["elements.L.y_end"]])
    assert np.abs(tip - [x, -y]).max() < 1e-8 * L
    assert abs(tip[1] + depth) < 1e-10 * L
    assert report["approach_steps"] >= 2  # it started inside the solid


def test_a_small_indentation_by_a_circle_is_linear_beam_theory():
    """A circle (R = L) pressed a depth d onto the tip from above: F / (3 EI d / L^3) - 1
    falls as d^2 (the order over d = L/100, L/200, L/400 is 2 within 0.1)."""
    errors = []
    for d in (L / 100, L / 200, L / 400):
        report = contact_report(
            strip(8, contacts=tip_point_against({"type": "circle", "centre": [L, L - d], "radius": L}))
        )
        force = np.linalg.norm(report["pairs"]["touch"]["force"])
        errors.append(abs(force / (3 * EI * d / L**3) - 1))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[0] < 1e-2 and np.all(np.abs(orders - 2) < 0.1), (errors, orders)


def test_a_cantilever_wrapped_onto_a_cylinder_has_its_curvature():
    """A drum of radius R under the clamp, tangent to the strip's underside there; a large
    downward tip force wraps the strip onto it. Where the underside lies on the drum the
    centre line's curvature is 1 / (R + h/2) to 1e-6, on every element clear of the lift-off
    point's neighbour (at the lift-off a concentrated force acts inside an element, whose
    error decays over the next elements); the wrapped part covers at least three elements."""
    radius, intervals = 0.05, 20
    contacts = {
        "objects": {"drum": {"type": "circle", "centre": [0, -radius - H / 2], "radius": radius}},
        "sites": {"underside": {"type": "surface", "link": "L", "side": "right"}},
        "pairs": {"wrap": {"site": "underside", "object": "drum"}},
    }
    mech = compile_mechanism(
        load_document(strip(intervals, 3, contacts, {"F": {"type": "force", "body": "tip", "force": [0, -100.0]}}))
    )
    problem = contact_problem(mech.structure)
    state = solve_state(problem, mech.p(), np.zeros(1))
    assert state.converged, state.message
    w = split(problem, state.v).w
    names = mech.graphs.energy_form.unknowns
    theta = np.concatenate([[0.0], [w[k] for k, name in enumerate(names) if ".theta" in name]])
    node_spacing = L / (3 * intervals)  # m between the nodes of cubic elements
    curvature = np.diff(theta) / node_spacing  # 1/m, from the nondimensional rotations (radians)
    on_drum = np.abs(np.asarray(problem.rows(w, mech.p())[0]).ravel()) < 1e-10
    wrapped = [e for e in range(intervals) if on_drum[3 * e : 3 * e + 3].all()]
    assert wrapped[:3] == [0, 1, 2] and len(wrapped) >= 4
    clear = wrapped[:-1]  # the last wrapped element neighbours the lift-off
    errors = [abs(curvature[k] * (radius + H / 2) + 1) for e in clear for k in range(3 * e, 3 * e + 3)]
    assert max(errors) < 1e-6, errors


def test_a_contact_free_state_is_the_shooting_solution():
    """An oblique tip force and an object that never touches: the contact analysis' state
    equals the shooting link's equilibrium to 1e-8 of L (tip position and angle, clamp moment)."""
    loads = {"F": {"type": "force", "body": "tip", "force": [-20.0, 45.0]}}
    far = tip_point_against({"type": "circle", "centre": [0.0, -0.2], "radius": 0.05})
    report = contact_report(strip(16, 3, far, loads))
    assert report["pairs"]["touch"]["state"] == "open"
    shooting = solve_equilibrium(
        compile_mechanism(load_document(strip(16, loads=loads, discretization="shooting"))),
        NewtonOptions(tol_residual=1e-13, tol_step=1e-13),
    ).outputs()
    for name in ("elements.L.x_end", "elements.L.y_end"):
        assert abs(report["outputs"][name] - shooting[name]) < 1e-8 * L
    assert abs(report["outputs"]["elements.L.angle_end"] - shooting["elements.L.angle_end"]) < 1e-8
    assert abs(report["outputs"]["elements.L.M_start"] - shooting["elements.L.M_start"]) < 1e-8 * 45.0 * L


@pytest.mark.parametrize("degree", [1, 2])
def test_the_contact_force_converges_at_the_discretization_order(degree):
    """Example I's jaw on the fixture (x_o = 67.81 mm, face contact): the insertion force at
    2, 4 and 8 elements of degree p against 16 cubic elements; the error falls as h^(2p)
    (the order within 0.35)."""
    from mechanisms import example_one

    def force(intervals: int, p: int) -> float:
        doc = example_one(67.81, intervals=intervals, degree=p)
        return contact_report(doc)["pairs"]["insertion"]["force"][0]

    reference = force(16, 3)
    errors = [abs(force(n, degree) - reference) for n in (2, 4, 8)]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 2 * degree) < 0.35), (errors, orders)
