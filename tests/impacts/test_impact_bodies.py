"""The bodies of an impact model are the statics' (models.impacts.coordinates): their mass
matrix comes from the statics' kinetic energy, gravity and loads from its load potential.
Checked by hand on a turned body whose mass centre is off its reference point, carrying an
offset force and a moment."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from impact_cases import csfh, parsed

from flexmech.models.impacts.model import impact_model

M, I_REF, C, ANGLE = 10.0, 0.25, np.array([0.03, -0.01]), 0.4  # mass, inertia about the reference point
F, OFFSET, MOMENT, G = np.array([3.0, -2.0]), np.array([0.05, 0.02]), 0.7, np.array([0.0, -9.81])


def _model():
    doc = csfh("6.1")
    doc["bodies"]["hinge"].update(mass=M, inertia=I_REF, center_of_mass=C.tolist(), angle=ANGLE)
    doc["units"]["angle"] = "rad"
    doc["loads"] = {
        "push": {"type": "force", "body": "hinge", "force": F.tolist(), "offset": OFFSET.tolist()},
        "turn": {"type": "moment", "body": "hinge", "moment": MOMENT},
    }
    return impact_model(parsed(doc)[0])


def _rot(a):
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


def test_the_mass_matrix_is_the_mass_and_the_inertia_about_the_mass_centre():
    model = _model()
    mass = np.asarray(ca.Function("m", [model.p], [model.mass])(model.book.parameter_vector())).ravel()
    assert mass == pytest.approx([M, M, I_REF - M * C @ C], rel=1e-14)


def test_the_kinetic_energy_is_the_rigid_bodys_at_any_pose():
    """T of the reference point's motion (inertia about it) equals 1/2 v.M v in the mass
    centre's coordinates, whatever the pose."""
    model = _model()
    kinetic = ca.Function("T", [model.q, model.v, model.p], [model.kinetic])
    p, rng = model.book.parameter_vector(), np.random.default_rng(4)
    for _ in range(5):
        q, v = rng.normal(size=3) * [0.01, 0.01, 1.0], rng.normal(size=3)
        arm = _rot(ANGLE + q[2]) @ C  # reference point to mass centre
        v_reference = v[:2] - v[2] * np.array([-arm[1], arm[0]])
        by_hand = (
            0.5 * M * v_reference @ v_reference
            + M * v[2] * (arm[0] * v_reference[1] - arm[1] * v_reference[0])
            + 0.5 * I_REF * v[2] ** 2
        )
        assert float(kinetic(q, v, p)) == pytest.approx(by_hand, rel=1e-12)


def test_gravity_an_offset_force_and_a_moment_give_the_hand_wrench_about_the_mass_centre():
    model = _model()
    force = ca.Function("Q", [model.q, model.v, model.p], [model.force])
    p = model.book.parameter_vector()
    for q in ([0.0, 0.0, 0.0], [0.002, -0.001, 0.3], [-0.004, 0.003, -1.2]):
        reference = np.array(q[:2]) + _rot(ANGLE) @ C - _rot(ANGLE + q[2]) @ C  # drawn at the origin
        at = reference + _rot(ANGLE + q[2]) @ OFFSET
        centre = np.array(q[:2]) + _rot(ANGLE) @ C
        arm = at - centre
        by_hand = np.concatenate([F + M * G, [arm[0] * F[1] - arm[1] * F[0] + MOMENT]])
        assert np.asarray(force(q, [0, 0, 0], p)).ravel() == pytest.approx(by_hand, rel=1e-12, abs=1e-12)


def test_a_driven_bodys_weight_works_through_its_drive_and_leaves_the_motion_alone():
    """A frame of mass m shaken by dy = A sin(w t) under gravity: its weight is part of the
    potential (the statics' load potential), its change is the input's work, m g dy at the
    end, and the pin moves as it does under a massless frame."""
    from flexmech.service.impacts.run import run_impacts

    A, w, until, mass = 0.03, 10.0, 0.15, 5.0
    reports = []
    for frame_mass in (None, mass):
        doc = csfh(
            "6.1",
            until=until,
            scheme="event_driven",
            step=1e-4,
            histories={"/loads/shake/dy": f"{A}*sin({w}*t)"},
            initial={"hinge": {"displacement": [0, 0, 0]}},
        )
        doc["loads"] = {"shake": {"type": "displacement", "body": "frame", "dx": 0, "dy": 0, "rotation": 0}}
        if frame_mass is not None:
            doc["bodies"]["frame"].update(mass=frame_mass, inertia=1.0)
        reports.append(run_impacts(*parsed(doc))[1])
    light, heavy = reports
    assert heavy["impacts"][0]["time"] == light["impacts"][0]["time"]
    assert heavy["coordinates"]["hinge.y"][-1] == pytest.approx(light["coordinates"]["hinge.y"][-1], rel=1e-12)
    weight_work = mass * 9.81 * A * np.sin(w * until)
    assert heavy["energies"]["gravity"][-1] - light["energies"]["gravity"][-1] == pytest.approx(weight_work, rel=1e-9)
    assert heavy["energies"]["input_work"][-1] == pytest.approx(weight_work, rel=1e-6)
    assert heavy["energy_balance_error"] < 1e-6
