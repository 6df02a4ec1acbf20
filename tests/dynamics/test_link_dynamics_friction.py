"""Friction of an elastic contact pair in link dynamics (models.contact.pair_forces): a disk
pushed across a floor slips and spins up exactly as rigid-body mechanics says, and the
friction's work closes the energy balance.

A disk (mass m, radius R, I = m R^2 / 2 about its centre) rests on a floor by a Hertz contact
(indented where K q^n = m g, so it starts in equilibrium) and is pushed at its centre by F >
3 mu m g: the contact point slips forward all the time, so Ambrosio's friction is mu m g
backwards (beyond v1 after the first tens of microseconds) and

    x = (F/m - mu g) t^2 / 2,   theta = -(mu g / R) t^2,   slip = (F/m - 3 mu g) t,
    work of friction = -mu m g (F/m - 3 mu g) t^2 / 2."""

from __future__ import annotations

import numpy as np
import pytest

from flexmech.models import compile_mechanism, load_document
from flexmech.service.analysis import run_analysis
from flexmech.service.solvers.newton import NewtonOptions

MASS, RADIUS, MU, PUSH, HERTZ, EXPONENT, G = 2.0, 0.05, 0.3, 30.0, 1e7, 1.5, 9.81
V0, V1, UNTIL = 1e-6, 1e-4, 0.4


def pushed_disk(friction) -> dict:
    indentation = (MASS * G / HERTZ) ** (1 / EXPONENT)
    return {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "gravity": [0, -G],
        "bodies": {
            "ground": {"fixed": True, "position": [0, 0]},
            "disk": {"position": [0, RADIUS], "mass": MASS, "inertia": MASS * RADIUS**2 / 2},
        },
        "loads": {"push": {"type": "force", "body": "disk", "force": [PUSH, 0]}},
        "contacts": {
            "sites": {"rim": {"type": "circle", "body": "disk", "centre": [0, 0], "radius": RADIUS}},
            "objects": {"floor": {"type": "half_plane", "point": [0, indentation], "normal": [0, 1]}},
            "pairs": {
                "rolling": {
                    "site": "rim",
                    "object": "floor",
                    "friction": friction,
                    "normal": {"law": "hertz", "stiffness": HERTZ, "exponent": EXPONENT},
                }
            },
        },
        "simulate": {"until": UNTIL, "step": 1e-3, "scheme": "newmark", "a1": 0.5, "a2": 0.5, "start": "rest"},
    }


def simulated(friction) -> dict:
    report = run_analysis(compile_mechanism(load_document(pushed_disk(friction))), "simulate", NewtonOptions())
    assert report["status"] == "finished", report["message"]
    return report


def test_a_pushed_disk_slips_and_spins_up_as_rigid_body_mechanics_says():
    """Average-acceleration steps of 1 ms: the accelerations are exact from the second step on
    (the first averages no friction at t = 0 with the full friction at its end, so the slip
    speed carries 1.5 mu g h more from then on); the friction's work per step is exactly -mu N
    times the slip distance (x + R theta) of the step, as the trapezoidal rule gives it."""
    report = simulated({"law": "ambrosio", "sliding": MU, "v0": V0, "v1": V1})
    h = report["step"]
    x, theta = (np.array(report["outputs"][f"bodies.disk.{c}"]) for c in ("x", "angle"))
    assert np.diff(x, 2)[1:] / h**2 == pytest.approx(PUSH / MASS - MU * G, rel=1e-6)
    assert np.diff(theta, 2)[1:] / h**2 == pytest.approx(-2 * MU * G / RADIUS, rel=1e-6)
    assert np.array(report["outputs"]["contacts.rolling.normal_force"]) == pytest.approx(MASS * G, rel=1e-6)
    slipped = np.diff(x + RADIUS * theta)[1:]
    assert np.diff(report["energies"]["friction_work"])[1:] == pytest.approx(-MU * MASS * G * slipped, rel=1e-6)
    # slip speed k h (F/m - 3 mu g) + 1.5 mu g h at step k >= 1 (the start's half step added 1.5 mu g h)
    k = np.arange(1, len(slipped) + 1)
    assert slipped == pytest.approx(h**2 * ((PUSH / MASS - 3 * MU * G) * (k + 0.5) + 1.5 * MU * G), rel=1e-6)
    assert report["energy_balance_error"] < 1e-6


def test_without_friction_the_disk_slides_without_turning_and_no_work_is_lost():
    report = simulated({"law": "none"})
    t = np.array(report["times"])
    assert report["outputs"]["bodies.disk.x"] == pytest.approx(0.5 * PUSH / MASS * t**2, rel=1e-9, abs=1e-12)
    assert np.abs(report["outputs"]["bodies.disk.angle"]).max() < 1e-12
    assert np.abs(report["energies"]["friction_work"]).max() == 0.0
    assert report["energy_balance_error"] < 1e-6


def test_a_run_stored_before_friction_had_its_row_resumes_with_none():
    """A simulation job stored its Resume with two works (inputs, damping) and a monitor
    without the contacts' friction and damping powers; it goes on with their works and powers
    at zero, the prescribed motions' forces where they were."""
    from flexmech.service.dynamics.stepping import Resume

    stored = {
        "step": 7,
        "state": [0.1, 0.2],
        "works": [3.0, 4.0],
        "monitor": [1.0, 2.0, 5.0, 6.0, 42.0],
        "time": 0.007,
        "h": None,
    }
    at = Resume.from_json(stored)
    assert at.works.tolist() == [3.0, 4.0, 0.0, 0.0]
    assert at.monitor.tolist() == [1.0, 2.0, 5.0, 6.0, 0.0, 0.0, 42.0]
    assert Resume.from_json(at.to_json()).monitor.tolist() == at.monitor.tolist()
