"""Coulomb friction along a path, against the closed form of a block on a moving floor: a
block (weight W = 10 N, its rotation held) rests on a floor (a half-plane) and is tied to
the ground by a horizontal spring k = 100 N/m; friction mu = 0.52. As the floor moves by s,
the block sticks to it (x = s, the spring's pull k s held by friction) until k x reaches
mu W, then slips (x = mu W / k, the friction force mu W). When the floor comes back, the
block sticks again from where it slipped: it moves with the floor until the spring pushes
with mu W the other way."""

from __future__ import annotations

import numpy as np

from flexmech.models import compile_mechanism, load_document
from flexmech.service.contact.path import follow, path_fields
from flexmech.service.contact.problem import contact_problem
from flexmech.service.contact.report import pairs_report, structure_outputs
from flexmech.service.contact.solve import ContactOptions

W, K, MU = 10.0, 100.0, 0.52
BLOCK_ON_FLOOR = {
    "units": {"length": "m", "force": "N", "angle": "rad"},
    "bodies": {"ground": {"fixed": True, "position": [0, 0]}, "block": {"position": [0, 0]}},
    "elements": {
        "drag": {"type": "spring", "from": "ground", "to": "block", "from_at": [-1, 0], "to_at": [0, 0], "stiffness": K}
    },
    "loads": {
        "upright": {"type": "displacement", "body": "block", "rotation": 0},
        "weight": {"type": "force", "body": "block", "force": [0, -W]},
    },
    "contacts": {
        "objects": {"floor": {"type": "half_plane", "point": [0, 0], "normal": [0, 1]}},
        "sites": {"foot": {"type": "jaw", "body": "block", "vertices": [[0, 0]]}},
        "pairs": {"rub": {"site": "foot", "object": "floor", "friction": MU}},
    },
}


def test_a_block_on_a_moving_floor_sticks_then_slips_then_sticks_again():
    there = np.linspace(0.0, 0.1, 21)
    back = np.linspace(0.1, 0.0, 21)[1:]
    mech = compile_mechanism(load_document(BLOCK_ON_FLOOR))
    problem = contact_problem(mech.structure)
    fields = path_fields(mech, [{"path": "/contacts/objects/floor/point/0", "values": [*there, *back]}])
    states = []
    for index, state in follow(mech, problem, fields, list(range(fields.states)), None, ContactOptions()):
        assert state.converged, state.message
        pair = pairs_report(mech, problem, state)["rub"]
        states.append((fields.at(index)[0], pair, structure_outputs(mech, problem, state)["bodies.block.x"]))
    slips_at = MU * W / K  # 0.052 m
    for s, pair, x in states[1:21]:  # the floor moving away
        assert abs(pair["normal_force"] - W) < 1e-9 * W
        if K * s <= MU * W:
            assert pair["state"] == "sticking" and abs(x - s) < 1e-12
            assert abs(pair["friction_force"] + K * s) < 1e-9 * W  # the tangent is -x: friction pulls +x
        else:
            assert pair["state"] == "slipping" and abs(x - slips_at) < 1e-12
            assert abs(abs(pair["friction_force"]) - MU * W) < 1e-9 * W
    for s, pair, x in states[21:]:  # the floor coming back: stuck again, from where it slipped
        assert pair["state"] == "sticking", s
        assert abs(x - (slips_at - (0.1 - s))) < 1e-12
        assert abs(pair["friction_force"] + K * x) < 1e-9 * W and abs(pair["friction_force"]) < MU * W
    assert [p["state"] for _, p, _ in states[1:21]].count("sticking") == 10
