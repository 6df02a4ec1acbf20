"""Two more contact examples of seed 002 Ch. 6, run through their documents' paths.

examples/gripper_ellipse_contact.json: Example II (the tapered finger with shear against the
moving ellipse, on the reading notes' assumed geometry): every state converges (mu = 0 and
0.5), the contact sits near s = 79 mm of the finger, shear changes the force; with a
zero-thickness finger (side centre_line) the contact NLP is the thesis' shooting formulation
of the same scene (Ch. 2 Example 3, Eqs. 2.26-2.27): a frictionless force along the
ellipse's normal, a straight (moment-free) finger beyond the contact, and the shooting
solution's force and contact point up to the resolution.

examples/two_finger_grip.json: two fingers closing symmetrically on a cylinder (mu = 0.3):
the pairs mirror each other to 1e-8 and the grip force grows monotonically.
"""

from __future__ import annotations

import json
from functools import lru_cache

import numpy as np
import pytest
from conftest import EXAMPLES
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

from flexmech.models import compile_mechanism, load_document
from flexmech.service.contact.kkt import split
from flexmech.service.contact.path import follow, path_fields
from flexmech.service.contact.problem import contact_problem
from flexmech.service.contact.report import pairs_report, structure_outputs
from flexmech.service.contact.solve import ContactOptions

ELLIPSE = "gripper_ellipse_contact.json"
GRIP = "two_finger_grip.json"
SEMI_AXES, Y_E = (49.53, 33.655), 120.65  # mm, Table 6.3
THESIS_RANGE = (-25.4, 50.8)  # x_e, mm: phi from 108 to 90 deg


def document(name: str) -> dict:
    return json.loads((EXAMPLES / name).read_text())


@lru_cache(maxsize=16)
def _run(text: str) -> tuple:
    doc = json.loads(text)
    mech = compile_mechanism(load_document(doc))
    problem = contact_problem(mech.structure)
    parameters = [p.model_dump(exclude_none=True) for p in mech.document.contacts.path.parameters]
    fields = path_fields(mech, parameters)
    states = []
    for index, state in follow(mech, problem, fields, list(range(fields.states)), None, ContactOptions()):
        states.append(
            {
                "values": fields.at(index),
                "converged": state.converged,
                "message": state.message,
                "state": state,
                "pairs": pairs_report(mech, problem, state),
            }
        )
    return mech, problem, states


def run(doc: dict) -> tuple:
    """(mechanism, contact problem, states) of the document's whole contacts.path."""
    return _run(json.dumps(doc, sort_keys=True))


def ellipse_doc(mu: float = 0.0, shear: bool = True, side: str | None = None) -> dict:
    doc = document(ELLIPSE)
    doc["contacts"]["pairs"]["grip"]["friction"] = mu
    doc["elements"]["finger"]["shear"] = shear
    if side is not None:
        doc["contacts"]["sites"]["face"]["side"] = side
    return doc


def touching(states: list[dict], pair: str) -> list[dict]:
    return [s for s in states if s["pairs"][pair]["state"] != "open"]


def in_thesis_range(s: dict) -> bool:
    return THESIS_RANGE[0] - 1e-9 <= s["values"][0] <= THESIS_RANGE[1] + 1e-9


# Example II ------------------------------------------------------------------------------------


@pytest.mark.parametrize("mu", [0.0, 0.5])
def test_example_two_converges_at_every_state_from_a_contact_free_start(mu):
    """81 states, x_e from 76.2 to -25.4 mm with the hub turning from phi = 84 to 108 deg:
    every one converges; the first is contact-free, the contact starts near x_e = 65 mm and
    holds to the end; friction never exceeds mu F_n and equals it where the pair slips."""
    _, _, states = run(ellipse_doc(mu))
    assert len(states) == 81
    for s in states:
        assert s["converged"], (s["values"], s["message"])
    assert states[0]["pairs"]["grip"]["state"] == "open"
    first = touching(states, "grip")[0]["values"][0]
    assert 60.0 < first < 70.0
    assert all(s["pairs"]["grip"]["state"] != "open" for s in states if s["values"][0] <= first)
    end = states[-1]
    assert end["values"][0] == pytest.approx(-25.4) and end["values"][1] == pytest.approx(23.999952)
    for s in touching(states, "grip"):
        pair = s["pairs"]["grip"]
        assert abs(pair["friction_force"]) <= mu * pair["normal_force"] * (1 + 1e-9) + 1e-12
        if pair["state"] == "slipping":
            assert abs(abs(pair["friction_force"]) - mu * pair["normal_force"]) <= 1e-9 * pair["normal_force"]
    if mu > 0:
        assert sum(s["pairs"]["grip"]["state"] == "slipping" for s in states) > 60


def test_example_two_touches_the_finger_near_s_79_mm():
    """Over the thesis' x_e = -25.4 .. 50.8 mm the contact lies 70 to 90 mm along the finger's
    right side (the notes: near s = 79 mm for this geometry), at x_e = -25.4 mm (phi = 108 deg)
    within 5 mm of 79; the forces the description records."""
    _, _, states = run(ellipse_doc())
    ranged = [s for s in states if in_thesis_range(s)]
    assert len(ranged) == 61 and all(s["pairs"]["grip"]["state"] == "frictionless" for s in ranged)
    along = np.array([s["pairs"]["grip"]["site_parameter"] for s in ranged])
    assert np.all((along >= 70.0) & (along <= 90.0 + 1e-9)), along
    last = states[-1]["pairs"]["grip"]
    assert abs(last["site_parameter"] - 79.0) < 5.0
    assert last["normal_force"] == pytest.approx(35.63, rel=1e-3)
    forces = np.array([s["pairs"]["grip"]["normal_force"] for s in ranged])
    assert forces.min() == pytest.approx(5.69, rel=1e-3) and forces.max() == pytest.approx(36.10, rel=1e-3)
    # the contact point is on the ellipse, the force pushes the finger away from it
    point, force = np.array(last["point"]), np.array(last["force"])
    assert abs(last["gap"]) <= 1e-9
    assert force @ (point - [-25.4, Y_E]) > 0


def test_shear_changes_the_contact_force():
    """The same path without shear: every touching state of the thesis' range differs from
    the Timoshenko finger's by more than 0.1 % (the finger is 30 to 17 mm thick over 90 mm)."""
    _, _, with_shear = run(ellipse_doc(shear=True))
    _, _, without = run(ellipse_doc(shear=False))
    assert all(s["converged"] for s in without)
    compared = 0
    for a, b in zip(with_shear, without):
        assert a["values"] == b["values"]
        if not in_thesis_range(a):
            continue
        fa, fb = a["pairs"]["grip"]["normal_force"], b["pairs"]["grip"]["normal_force"]
        assert fa > 0 and fb > 0
        assert abs(fb / fa - 1) > 1e-3, a["values"]
        compared += 1
    assert compared == 61


# Example II with a zero-thickness finger: the thesis' shooting formulation (Ch. 2 Example 3)


E_MPA, B_MM, LENGTH, HUB = 4.8, 25.0, 90.0, 30.0
CENTRE_LINE_ELEMENTS = 24


def _EI(s: float) -> float:
    h = 30.0 + (17.0 - 30.0) * s / LENGTH
    return E_MPA * B_MM * h**3 / 12.0


def _ellipse_gradient(point: np.ndarray, x_e: float) -> np.ndarray:
    return np.array([2 * (point[0] - x_e) / SEMI_AXES[0] ** 2, 2 * (point[1] - Y_E) / SEMI_AXES[1] ** 2])


def _shoot(unknowns: np.ndarray, phi: float) -> np.ndarray:
    """Euler's elastica from the clamp on the hub to the contact point s_c under a force
    (F_x, F_y) there: state (x, y, psi, M) at s_c. Unknowns: clamp moment, F_x, F_y, s_c."""
    M0, Fx, Fy, s_c = unknowns

    def rhs(s, z):
        return [np.cos(z[2]), np.sin(z[2]), z[3] / _EI(s), -(np.cos(z[2]) * Fy - np.sin(z[2]) * Fx)]

    start = [HUB * np.cos(phi), HUB * np.sin(phi), phi, M0]
    return solve_ivp(rhs, (0.0, s_c), start, rtol=1e-12, atol=1e-12).y[:, -1]


def _shooting_conditions(unknowns: np.ndarray, x_e: float, phi: float) -> list[float]:
    """Eqs. 2.26-2.27: no moment at the contact (the rest of the finger is unloaded), the
    contact on the ellipse, the finger tangent to it there, the force along its normal."""
    x, y, psi, M = _shoot(unknowns, phi)
    g = _ellipse_gradient(np.array([x, y]), x_e)
    size = np.hypot(*g)
    return [
        M / 100.0,
        ((x - x_e) / SEMI_AXES[0]) ** 2 + ((y - Y_E) / SEMI_AXES[1]) ** 2 - 1,
        (np.cos(psi) * g[0] + np.sin(psi) * g[1]) / size,
        (unknowns[1] * g[1] - unknowns[2] * g[0]) / size,
    ]


def _surface_u(intervals: int, degree: int) -> np.ndarray:
    """u of the link's drawn points: its start, the contact points (degree Gauss points per
    element), its end."""
    xi = (np.polynomial.legendre.leggauss(degree)[0] + 1) / 2
    inner = [(e + x) / intervals for e in range(intervals) for x in xi]
    return np.array([0.0, *inner, 1.0])


def centre_line_states():
    """The document's path with a zero-thickness finger (side centre_line, no shear, no
    friction) at 24 cubic elements: contact points 1.25 mm apart, so the contact (near
    s = 84-89 mm) usually has whole elements beyond it."""
    doc = ellipse_doc(mu=0.0, shear=False, side="centre_line")
    doc["elements"]["finger"]["intervals"] = CENTRE_LINE_ELEMENTS
    mech, problem, states = run(doc)
    assert all(s["converged"] for s in states)
    return doc, mech, problem, touching(states, "grip")


def _single_row(problem, state) -> bool:
    rows = state.mode.active[problem.n_element_in :] > 0.5
    return int(rows.sum()) == 1


def test_a_frictionless_centre_line_contact_pushes_along_the_ellipse_normal():
    """Zero thickness, no friction, no shear: where one point of the finger carries the
    contact (most states), it lies on the ellipse (1e-9) and the force on the finger is
    along the ellipse's outward normal there (1e-8), pushing away from the ellipse."""
    _, _, problem, states = centre_line_states()
    single = [s for s in states if _single_row(problem, s["state"])]
    assert len(states) > 50 and len(single) >= 0.75 * len(states)
    for s in single:
        pair, x_e = s["pairs"]["grip"], s["values"][0]
        point, force = np.array(pair["point"]), np.array(pair["force"])
        on_ellipse = ((point[0] - x_e) / SEMI_AXES[0]) ** 2 + ((point[1] - Y_E) / SEMI_AXES[1]) ** 2
        assert on_ellipse == pytest.approx(1, abs=1e-9)
        normal = _ellipse_gradient(point, x_e)
        normal /= np.linalg.norm(normal)
        assert abs(force[0] * normal[1] - force[1] * normal[0]) <= 1e-8 * np.linalg.norm(force), x_e
        assert force @ normal > 0


def test_the_finger_beyond_a_centre_line_contact_is_straight():
    """No moment beyond the contact: every element after the one holding the contact keeps
    one cross-section angle (its normals equal the tip's to 1e-8) and its centre line lies
    on the tip's tangent line (1e-8 of the length)."""
    doc, _, problem, states = centre_line_states()
    finger = doc["elements"]["finger"]
    n, degree = finger["intervals"], finger["degree"]
    u = _surface_u(n, degree)
    ((name, count),) = problem.drawn_links
    assert name == "finger" and count == len(u)
    checked = 0
    for s in states:
        along = s["pairs"]["grip"]["site_parameter"] / LENGTH
        if not _single_row(problem, s["state"]) or along > 1 - 1 / n:
            continue  # two points share the contact, or it is in the last element
        w = split(problem, s["state"].v).w
        outline = np.asarray(problem.drawing(w, s["state"].p)[1], dtype=float).reshape(2, -1, 3)
        centres, lefts = outline[:, :, 0].T, outline[:, :, 1].T
        normals = (lefts - centres) / np.linalg.norm(lefts - centres, axis=1)[:, None]
        beyond = u >= (np.floor(along * n) + 1) / n - 1e-12
        assert beyond.sum() >= degree + 1
        tip_normal, tip = normals[-1], centres[-1]
        tangent = np.array([tip_normal[1], -tip_normal[0]])
        scale = np.linalg.norm(centres[-1] - centres[0])
        for k in np.flatnonzero(beyond):
            assert np.linalg.norm(normals[k] - tip_normal) <= 1e-8, (s["values"], u[k])
            offset = centres[k] - tip
            assert abs(offset @ tip_normal) <= 1e-8 * scale, (s["values"], u[k])
            assert offset @ tangent <= 1e-12 * scale  # behind the tip
        checked += 1
    assert checked >= 15


@pytest.mark.parametrize("x_e", [35.56, 15.24, -5.08])
def test_the_centre_line_contact_is_the_thesis_shooting_solution(x_e):
    """The thesis' shooting formulation of the same scene (Eqs. 2.26-2.27: contact point
    unknown, no moment there, on the ellipse, tangent to it, force normal), solved here
    independently by scipy from the NLP's state, agrees with the contact NLP up to the
    resolution of the discrete contact points (24 cubic elements: 1.25 mm apart): the
    contact within one spacing, the force within 2.5 % in size and 3 deg in direction."""
    doc, mech, problem, states = centre_line_states()
    (s,) = [s for s in states if abs(s["values"][0] - x_e) < 1e-6]
    pair = s["pairs"]["grip"]
    outputs = structure_outputs(mech, problem, s["state"])
    phi = np.radians(doc["bodies"]["hub"]["angle"] + s["values"][1])
    guess = [outputs["elements.finger.M_start"], pair["force"][0], pair["force"][1], pair["site_parameter"]]
    solution, _, ok, message = fsolve(_shooting_conditions, guess, args=(x_e, phi), full_output=True, xtol=1e-13)
    assert ok == 1 and np.max(np.abs(_shooting_conditions(solution, x_e, phi))) < 1e-9, message
    force, s_c = solution[1:3], solution[3]
    spacing = LENGTH / (doc["elements"]["finger"]["intervals"] * doc["elements"]["finger"]["degree"])
    assert 70.0 < s_c < 90.0
    assert abs(pair["site_parameter"] - s_c) < spacing
    assert np.linalg.norm(pair["force"]) == pytest.approx(np.linalg.norm(force), rel=0.025)
    ours = np.array(pair["force"])
    assert np.degrees(np.arccos(ours @ force / np.linalg.norm(ours) / np.linalg.norm(force))) < 3


# The two-finger grip --------------------------------------------------------------------------


def grip_states() -> list[dict]:
    _, _, states = run(document(GRIP))
    return states


def test_the_two_finger_grip_converges_from_open_to_a_firm_grip():
    """49 states, the jaws closing 0 .. 12 mm each: all converge, the first ones are open
    (4.5 mm gap), both pairs touch from dx = 4.75 mm on and slip with |F_t| = 0.3 F_n."""
    states = grip_states()
    assert len(states) == 49
    for s in states:
        assert s["converged"], (s["values"], s["message"])
        assert s["values"][1] == -s["values"][0]
    opened = [s for s in states if s["values"][0] <= 4.5 + 1e-9]
    assert all(p["state"] == "open" for s in opened for p in s["pairs"].values())
    closed = [s for s in states if s["values"][0] >= 4.75 - 1e-9]
    assert len(closed) == 30
    for s in closed:
        for pair in s["pairs"].values():
            assert pair["state"] == "slipping"
            assert abs(abs(pair["friction_force"]) - 0.3 * pair["normal_force"]) <= 1e-9 * pair["normal_force"]


def test_the_two_fingers_mirror_each_other():
    """Mirror symmetry about x = 0 at every touching state, to 1e-8 relative: equal normal
    forces, opposite horizontal and equal vertical forces, opposite friction (each measured
    along its own tangent), mirrored contact points, the same place along each finger."""
    checked = 0
    for s in grip_states():
        left, right = s["pairs"]["left_grip"], s["pairs"]["right_grip"]
        assert left["state"] == right["state"]
        if left["state"] == "open":
            continue
        size = left["normal_force"]
        assert abs(left["normal_force"] - right["normal_force"]) <= 1e-8 * size
        assert abs(left["force"][0] + right["force"][0]) <= 1e-8 * size
        assert abs(left["force"][1] - right["force"][1]) <= 1e-8 * size
        assert abs(left["friction_force"] + right["friction_force"]) <= 1e-8 * size
        assert abs(left["point"][0] + right["point"][0]) <= 1e-8 * 60
        assert abs(left["point"][1] - right["point"][1]) <= 1e-8 * 60
        assert abs(left["site_parameter"] - right["site_parameter"]) <= 1e-8 * 60
        assert left["force"][0] < 0 < right["force"][0]  # the cylinder pushes each finger outwards
        checked += 1
    assert checked == 30


def test_the_grip_force_grows_monotonically_while_closing():
    """Each step of 0.25 mm closer raises the grip (normal) force, from first contact to
    8.96 N per finger at dx = 12 mm (the description's value)."""
    closed = [s for s in grip_states() if s["pairs"]["left_grip"]["state"] != "open"]
    forces = np.array([s["pairs"]["left_grip"]["normal_force"] for s in closed])
    assert forces[0] < 0.5 and np.all(np.diff(forces) > 0)
    assert forces[-1] == pytest.approx(8.958, rel=1e-3)


def test_the_jaws_reactions_balance_the_contact_forces():
    """Each jaw holds its finger against the cylinder: its reaction force is minus the
    contact force on the finger (the finger is otherwise unloaded)."""
    mech, problem, states = run(document(GRIP))
    last = states[-1]
    outputs = structure_outputs(mech, problem, last["state"])
    force = np.array(last["pairs"]["left_grip"]["force"])
    reaction = np.array([outputs["reactions.left_jaw.Fx"], outputs["reactions.left_jaw.Fy"]])
    assert np.linalg.norm(reaction + force) <= 1e-8 * np.linalg.norm(force)
    # the finger's start wrench carries the contact force: n(0) = F and M(0) = (P - start) x F
    start = np.array([outputs["elements.left_finger.x_start"], outputs["elements.left_finger.y_start"]])
    arm = np.array(last["pairs"]["left_grip"]["point"]) - start
    internal = np.array([outputs["elements.left_finger.h"], outputs["elements.left_finger.v"]])
    assert np.linalg.norm(internal - force) <= 1e-8 * np.linalg.norm(force)
    moment = arm[0] * force[1] - arm[1] * force[0]
    assert abs(outputs["elements.left_finger.M_start"] - moment) <= 1e-8 * abs(moment)
    assert abs(outputs["reactions.left_jaw.M"] + moment) <= 1e-8 * abs(moment)
