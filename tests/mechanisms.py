"""Documents several test rooms share: the pinned four-bar with springs (statics), the chain of
springs under gravity (the energy form, saved graphs), and Example I of seed 002 Ch. 6 (contact,
contact in design)."""

from __future__ import annotations

import json

from conftest import EXAMPLES


def four_bar() -> dict:
    """Ground - crank - coupler - rocker joined by pins, two torsional springs (one linear,
    one nonlinear), a translational spring from the coupler to ground, a force and a moment
    (units: m, N, rad)."""
    return {
        "units": {"length": "m", "force": "N", "angle": "rad"},
        "bodies": {
            "ground": {"fixed": True, "position": [0, 0]},
            "crank": {"position": [0, 0.5]},
            "coupler": {"position": [0.6, 1.0]},
            "rocker": {"position": [1.2, 0.5]},
        },
        "elements": {
            "A": {"type": "pin", "from": "ground", "to": "crank", "at": [0, 0]},
            "B": {"type": "pin", "from": "crank", "to": "coupler", "at": [0, 1.0]},
            "C": {"type": "pin", "from": "coupler", "to": "rocker", "at": [1.2, 1.0]},
            "D": {"type": "pin", "from": "ground", "to": "rocker", "at": [1.2, 0]},
            "kA": {"type": "spring", "kind": "torsional", "from": "ground", "to": "crank", "stiffness": 4.0},
            "kD": {
                "type": "spring",
                "kind": "torsional",
                "from": "ground",
                "to": "rocker",
                "law": "k * x + c * x**3",
                "parameters": {"k": 2.0, "c": 30.0},
            },
            "pull": {
                "type": "spring",
                "from": "ground",
                "to": "coupler",
                "from_at": [0.6, -0.4],
                "to_at": [0.6, 1.0],
                "law": "s * tanh(x / w)",
                "parameters": {"s": 3.0, "w": 0.2},
            },
        },
        "loads": {
            "push": {"type": "force", "body": "coupler", "at": [0.3, 1.0], "force": [1.5, -2.0]},
            "turn": {"type": "moment", "body": "rocker", "moment": 0.4},
        },
        "outputs": {
            "ground": {"type": "reaction", "body": "ground"},
            "P": {"type": "point", "body": "coupler", "at": [0.3, 1.0]},
            "Q": {"type": "point", "body": "coupler", "at": [0.6, 1.0]},
        },
    }


def chain() -> dict:
    """Two bodies in a chain of springs (a linear translational one between offset points,
    a nonlinear one and a torsional one), the second body's rotation prescribed, a force off
    a reference point, and both bodies' weights under gravity (units: m, N, rad, kg)."""
    return {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "gravity": [0.0, -9.81],
        "bodies": {
            "ground": {"fixed": True, "position": [0, 0]},
            "b1": {"position": [1.0, 0.0], "mass": 0.2, "center_of_mass": [0.1, 0.05]},
            "b2": {"position": [2.0, 0.2], "angle": 0.3, "mass": 0.1},
        },
        "elements": {
            "s1": {
                "type": "spring",
                "from": "ground",
                "to": "b1",
                "from_at": [0, 0.3],
                "to_at": [0.9, 0.2],
                "stiffness": 40.0,
            },
            "s2": {
                "type": "spring",
                "from": "ground",
                "to": "b1",
                "from_at": [0.5, -0.6],
                "stiffness": 25.0,
                "rest": 0.9,
            },
            "s3": {
                "type": "spring",
                "from": "b1",
                "to": "b2",
                "to_at": [2.0, 0.4],
                "law": "k * x + c * x**3",
                "parameters": {"k": 30.0, "c": 400.0},
            },
            "s4": {"type": "spring", "kind": "torsional", "from": "b1", "to": "b2", "stiffness": 2.0},
            "s5": {"type": "spring", "from": "ground", "to": "b2", "from_at": [2.5, -0.5], "stiffness": 15.0},
        },
        "loads": {
            "pull": {"type": "force", "body": "b1", "offset": [0.2, -0.1], "force": [2.0, 1.0]},
            "tilt": {"type": "displacement", "body": "b2", "rotation": 0.05},
        },
    }


def example_one(x_o: float | None = None, mu: float = 0.0, intervals: int = 8, degree: int = 3) -> dict:
    doc = json.loads((EXAMPLES / "gripper_jaw_contact.json").read_text())
    if x_o is not None:
        doc["contacts"]["objects"]["fixture"]["centre"][0] = x_o
    doc["contacts"]["pairs"]["insertion"]["friction"] = mu
    doc["elements"]["finger"].update(intervals=intervals, degree=degree)
    return doc


def sprung_bodies(bodies: list[str], ground: str = "ground") -> dict:
    """Bodies on springs, each held alone: body k sits at (3 (k + 1), 0) mm, tied to `ground` by
    a translational spring along x and one along y (100 N/mm each) and a torsional spring
    (50 N mm/rad); three unknowns per body, so an export of it compiles in about a second.
    Loads and outputs are the caller's (units: mm, N, rad)."""
    doc: dict = {
        "name": "sprung bodies",
        "units": {"length": "mm", "force": "N", "angle": "rad"},
        "bodies": {ground: {"fixed": True, "position": [0, 0]}},
        "elements": {},
        "loads": {},
        "outputs": {},
    }
    for k, body in enumerate(bodies):
        x = 3.0 * (k + 1)
        doc["bodies"][body] = {"position": [x, 0]}
        doc["elements"][f"along x {k}"] = {
            "type": "spring",
            "from": ground,
            "to": body,
            "from_at": [x - 1, 0],
            "to_at": [x, 0],
            "stiffness": 100,
        }
        doc["elements"][f"along y {k}"] = {
            "type": "spring",
            "from": ground,
            "to": body,
            "from_at": [x, -1],
            "to_at": [x, 0],
            "stiffness": 100,
        }
        doc["elements"][f"turn {k}"] = {
            "type": "spring",
            "kind": "torsional",
            "from": ground,
            "to": body,
            "stiffness": 50,
        }
    return doc
