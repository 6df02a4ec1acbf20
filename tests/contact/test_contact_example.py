"""Example I of seed 002 Ch. 6 (the jaw against the circular fixture, geometry of the reading
notes, examples/gripper_jaw_contact.json) over the whole insertion, mu = 0 and 0.5: at every
state the clamp balances the contact force (Eq. 6.6), a slipping contact's friction is
mu F_n and opposes the sliding, the contact runs along the face and then sits on the crest,
and the insertion force is converged in resolution."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest
from mechanisms import example_one

from flexmech.models import compile_mechanism, load_document
from flexmech.service.contact.path import follow, path_fields
from flexmech.service.contact.problem import contact_problem
from flexmech.service.contact.report import pairs_report, structure_outputs
from flexmech.service.contact.solve import ContactOptions

FACE = float(np.hypot(19.0, 10.4598 - 1.6))  # |ab|, mm


@lru_cache(maxsize=8)
def insertion(mu: float, intervals: int = 8, values: tuple[float, ...] | None = None) -> list[dict]:
    """Every state of the insertion path (the document's, or x_o through `values`)."""
    mech = compile_mechanism(load_document(example_one(mu=mu, intervals=intervals)))
    problem = contact_problem(mech.structure)
    parameters = [p.model_dump(exclude_none=True) for p in mech.document.contacts.path.parameters]
    if values is not None:
        parameters = [{"path": parameters[0]["path"], "values": list(values)}]
    fields = path_fields(mech, parameters)
    out = []
    for index, state in follow(mech, problem, fields, list(range(fields.states)), None, ContactOptions()):
        assert state.converged, (fields.at(index), state.message)
        out.append(
            {
                "x_o": fields.at(index)[0],
                "pair": pairs_report(mech, problem, state)["insertion"],
                "outputs": structure_outputs(mech, problem, state),
            }
        )
    return out


def touching(states: list[dict]) -> list[dict]:
    largest = max(s["pair"]["normal_force"] for s in states)
    return [s for s in states if s["pair"]["state"] != "open" and s["pair"]["normal_force"] > 1e-6 * largest]


@pytest.mark.parametrize("mu", [0.0, 0.5])
def test_the_clamp_moment_is_the_moment_of_the_contact_force(mu):
    """Eq. 6.6 at every touching state (about 80 of the 101): the clamp's reaction moment and
    the link's moment at the clamp both equal the moment of the contact force (friction
    included) about the clamp, to 1e-8 relative."""
    states = touching(insertion(mu))
    assert len(states) > 70
    for s in states:
        point, force = np.array(s["pair"]["point"]), np.array(s["pair"]["force"])
        moment = point[0] * force[1] - point[1] * force[0]  # the clamp is at the origin
        assert abs(s["outputs"]["elements.finger.M_start"] - moment) <= 1e-8 * abs(moment), s["x_o"]
        assert abs(s["outputs"]["reactions.clamp.M"] + moment) <= 1e-8 * abs(moment), s["x_o"]


def test_a_slipping_contact_carries_mu_times_the_normal_force_against_its_sliding():
    """mu = 0.5: every touching state slips; |F_t| = mu F_n to 1e-9 relative, and F_t opposes
    the jaw's slide relative to the fixture over the step from the previous state, computed
    here from the tip body's motion (the jaw's material point) and the fixture's."""
    states = insertion(0.5)
    checked = 0
    for before, after in zip(states, states[1:]):
        pair = after["pair"]
        if pair not in [s["pair"] for s in touching(states)] or before["pair"]["state"] == "open":
            continue
        assert pair["state"] == "slipping"
        assert abs(abs(pair["friction_force"]) - 0.5 * pair["normal_force"]) <= 1e-9 * pair["normal_force"]
        point, normal = np.array(pair["point"]), np.array(pair["normal"])
        tangent = np.array([-normal[1], normal[0]])
        o_new = np.array([after["outputs"]["bodies.tip.x"], after["outputs"]["bodies.tip.y"]])
        o_old = np.array([before["outputs"]["bodies.tip.x"], before["outputs"]["bodies.tip.y"]])
        turn = np.radians(after["outputs"]["bodies.tip.angle"] - before["outputs"]["bodies.tip.angle"])
        back = np.array([[np.cos(turn), np.sin(turn)], [-np.sin(turn), np.cos(turn)]])
        jaw_point_before = o_old + back @ (point - o_new)  # the jaw's material point, a step earlier
        fixture_moved = np.array([after["x_o"] - before["x_o"], 0.0])
        slide = (point - jaw_point_before - fixture_moved) @ tangent
        assert slide * pair["friction_force"] < 0, after["x_o"]
        checked += 1
    assert checked > 70


@pytest.mark.parametrize("mu", [0.0, 0.5])
def test_the_contact_runs_along_the_face_then_sits_on_the_crest(mu):
    """The site parameter (arc length along the jaw from its heel at the origin, over the
    nose) grows along face ab while the fixture moves in, then stays at the crest b."""
    states = touching(insertion(mu))
    along = np.array([s["pair"]["site_parameter"] for s in states])
    heel_to_nose = float(np.hypot(19.0, 1.6))
    crest = heel_to_nose + FACE
    on_face = along < crest - 1e-6
    assert on_face[0] and not on_face[-1]
    first_crest = int(np.argmin(on_face))
    assert np.all(on_face[:first_crest]) and np.all(np.abs(along[first_crest:] - crest) < 1e-6)
    assert np.all(np.diff(along[:first_crest]) > 0)


REPORTED = (75.0, 67.81, 64.0, 60.0, 52.0)


@pytest.mark.parametrize("mu", [0.0, 0.5])
def test_the_insertion_force_is_converged_in_resolution(mu):
    """8 and 16 cubic elements agree on the insertion force at the reported x_o to 1e-7
    relative (the path through them, so friction slides the same way)."""
    values = tuple(np.concatenate([np.linspace(80, 75, 11), REPORTED[1:]]).tolist())
    coarse, fine = insertion(mu, 8, values), insertion(mu, 16, values)
    for a, b in zip(coarse[-5:], fine[-5:]):
        assert abs(a["pair"]["force"][0] - b["pair"]["force"][0]) <= 1e-7 * abs(b["pair"]["force"][0])
