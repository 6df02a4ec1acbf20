"""Damped normal laws in link dynamics (models.contact.pair_forces), their onsets located
(service.dynamics.onsets): a block kicked along a rail coasts into a stop and rebounds with
the law's exact effective restitution, which depends on the law's damping factor alone
(models.contact.laws.penalty.effective_restitution, itself checked against a quadrature in
tests/impacts/test_impacts.py); the contacts' damping work is the kinetic energy lost."""

from __future__ import annotations

import numpy as np
import pytest

from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.models.contact.laws import NORMAL_LAWS
from flexmech.models.contact.laws.penalty import effective_restitution
from flexmech.service.analysis import run_analysis
from flexmech.service.solvers.newton import NewtonOptions

MASS, HERTZ, PAD, GAP, KICK, KICK_TIME = 2.0, 2e6, 0.02, 0.03, 10.0, 0.1  # kg, N/m^1.5, m, m, N, s


def kicked_block(law: str, step: float = 2e-5, **simulate) -> dict:
    return {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "bodies": {
            "wall": {"fixed": True, "position": [0, 0]},
            "block": {"position": [0.5, 0], "mass": MASS, "inertia": 0.01},
        },
        "elements": {"rail": {"type": "slider", "from": "wall", "to": "block", "angle": 0}},
        "loads": {"kick": {"type": "force", "body": "block", "force": [KICK, 0]}},
        "contacts": {
            "sites": {"pad": {"type": "circle", "body": "block", "centre": [0, 0], "radius": PAD}},
            "objects": {"stop": {"type": "half_plane", "point": [0.5 + PAD + GAP, 0], "normal": [-1, 0]}},
            "pairs": {
                "touch": {
                    "site": "pad",
                    "object": "stop",
                    "normal": {"law": law, "stiffness": HERTZ, "exponent": 1.5, "restitution": 0.9},
                }
            },
        },
        "simulate": {
            "until": 0.15,
            "step": step,
            "scheme": "newmark",
            "a1": 0.5,
            "a2": 0.5,
            "start": "rest",
            "histories": {
                "/loads/kick/force/0": {"table": [[0, KICK], [KICK_TIME, KICK], [KICK_TIME + 1e-9, 0], [1, 0]]}
            },
            **simulate,
        },
    }


def simulated(doc: dict) -> dict:
    report = run_analysis(compile_mechanism(load_document(doc)), "simulate", NewtonOptions())
    assert report["status"] == "finished", report["message"]
    return report


def _speeds(report) -> tuple[float, float, np.ndarray]:
    """(speed in, speed out, indentations): from the coasting before and after the contact."""
    t, x = np.array(report["times"]), np.array(report["outputs"]["bodies.block.x"])
    q = np.array(report["outputs"]["contacts.touch.indentation"])
    inside = np.flatnonzero(q > 0)
    first, last = inside[0], inside[-1]
    before = slice(first - 3, first - 1)  # coasting: two states before the onset's
    after = slice(last + 2, last + 4)
    speed_in = np.diff(x[before])[0] / np.diff(t[before])[0]
    speed_out = -np.diff(x[after])[0] / np.diff(t[after])[0]
    return speed_in, speed_out, q


@pytest.mark.parametrize("law", ["lankarani_nikravesh", "hunt_crossley", "flores"])
def test_a_damped_law_rebounds_with_its_exact_restitution_from_its_located_onset(law):
    report = simulated(kicked_block(law))
    speed_in, speed_out, q = _speeds(report)
    exact = effective_restitution(NORMAL_LAWS[law].damping_factor(0.9))
    assert speed_out / speed_in == pytest.approx(exact, rel=1e-5)  # 5e-7 to 7e-7 measured
    assert np.abs(q).min() < 1e-12  # a state on the onset itself
    lost = 0.5 * MASS * (speed_out**2 - speed_in**2)
    assert report["energies"]["contact_damping_work"][-1] == pytest.approx(lost, rel=1e-4)
    assert report["energy_balance_error"] < 1e-5
    # the reported normal force is the whole (its elastic part alone does no work over the contact)
    force, x = np.array(report["outputs"]["contacts.touch.normal_force"]), np.array(report["outputs"]["bodies.block.x"])
    work = -np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(x))
    assert work == pytest.approx(lost, rel=1e-3)


def test_hertz_rebounds_whole_and_the_linear_laws_jump_is_refused_saying_why():
    report = simulated(kicked_block("hertz"))
    speed_in, speed_out, _ = _speeds(report)
    assert speed_out / speed_in == pytest.approx(1.0, rel=1e-4)
    assert report["energies"]["contact_damping_work"][-1] == 0.0
    doc = kicked_block("linear")
    doc["contacts"]["pairs"]["touch"]["normal"] = {"law": "linear", "stiffness": 2e4, "damping": 20.0}
    with pytest.raises(MechanismError) as caught:
        simulated(doc)
    assert caught.value.pointer == "/contacts/pairs/touch/normal/law"
    assert "does not take the normal law 'linear'" in caught.value.problem


def test_an_adaptive_run_lands_on_the_onset_too():
    report = simulated(kicked_block("lankarani_nikravesh", step=1e-4, tolerance=1e-7))
    speed_in, speed_out, q = _speeds(report)
    exact = effective_restitution(NORMAL_LAWS["lankarani_nikravesh"].damping_factor(0.9))
    assert speed_out / speed_in == pytest.approx(exact, rel=1e-4)  # 1.7e-5 measured
    assert np.abs(q).min() < 1e-12
