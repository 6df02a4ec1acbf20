"""Contact pairs with Hertz's elastic law in the statics and in link dynamics
(models.contact.elastic_pairs): a block on a spring pushed against a stop, and the Table 4.1
steel rod bent up against a stop above its tip. The equilibrium solve meets the force balance
k x + K (x - gap)^n = F exactly; an undamped run reaches the indentation where the work of
the push equals the energy stored; a damped run settles where the equilibrium solve stands."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service.analysis import run_analysis
from flexmech.service.solvers.newton import NewtonOptions

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SPRING, HERTZ, EXPONENT, GAP, PAD, PUSH = 400.0, 2e6, 1.5, 0.01, 0.02, 10.0  # N/m, N/m^1.5, 1, m, m, N


def block_against_a_stop(**fields) -> dict:
    """A 2 kg block on a spring and a slider along x, a pad of radius 20 mm on it, a stop 10 mm
    beyond the pad, pushed by 10 N."""
    return {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "bodies": {
            "wall": {"fixed": True, "position": [0, 0]},
            "block": {"position": [0.5, 0], "mass": 2.0, "inertia": 0.01},
        },
        "elements": {
            "spring": {"type": "spring", "from": "wall", "to": "block", "stiffness": SPRING},
            "rail": {"type": "slider", "from": "wall", "to": "block", "angle": 0},
        },
        "loads": {"push": {"type": "force", "body": "block", "force": [PUSH, 0]}},
        "contacts": {
            "sites": {"pad": {"type": "circle", "body": "block", "centre": [0, 0], "radius": PAD}},
            "objects": {"stop": {"type": "half_plane", "point": [0.5 + PAD + GAP, 0], "normal": [-1, 0]}},
            "pairs": {
                "touch": {
                    "site": "pad",
                    "object": "stop",
                    "normal": {"law": "hertz", "stiffness": HERTZ, "exponent": EXPONENT},
                }
            },
        },
        **fields,
    }


def analysed(doc: dict, analysis: str) -> dict:
    return run_analysis(compile_mechanism(load_document(doc)), analysis, NewtonOptions())


def test_the_equilibrium_solve_balances_the_spring_the_contact_and_the_push():
    report = analysed(block_against_a_stop(), "equilibrium")
    x = brentq(lambda x: SPRING * x + HERTZ * max(x - GAP, 0) ** EXPONENT - PUSH, 0, 0.1, xtol=1e-16)
    assert report["status"] == "converged"
    assert report["displacements"]["block.x"] == pytest.approx(x, rel=1e-9)
    assert report["outputs"]["contacts.touch.normal_force"] == pytest.approx(HERTZ * (x - GAP) ** EXPONENT, rel=1e-9)
    assert report["outputs"]["contacts.touch.indentation"] == pytest.approx(x - GAP, rel=1e-9)
    assert report["output_units"]["contacts.touch.normal_force"] == "N"
    assert report["outputs"]["reactions.wall.Fx"] == pytest.approx(-SPRING * x, rel=1e-9)  # the stop is fixed


def test_an_undamped_run_reaches_the_indentation_where_the_pushs_work_is_stored():
    """From rest, the push's work F (gap + q) equals k (gap + q)^2 / 2 + K q^(n+1) / (n+1) at the
    deepest indentation q; average-acceleration Newmark steps of 0.1 ms reach it to 1e-4."""
    doc = block_against_a_stop(simulate={"until": 0.6, "step": 1e-4, "scheme": "newmark", "a1": 0.5, "a2": 0.5})
    report = analysed(doc, "simulate")
    assert report["status"] == "finished", report["message"]
    deepest = brentq(
        lambda q: PUSH * (GAP + q) - SPRING * (GAP + q) ** 2 / 2 - HERTZ * q ** (EXPONENT + 1) / (EXPONENT + 1),
        1e-9,
        0.05,
        xtol=1e-16,
    )
    indentation = np.array(report["outputs"]["contacts.touch.indentation"])
    assert indentation.max() == pytest.approx(deepest, rel=1e-4)
    assert indentation[0] == pytest.approx(-GAP, rel=1e-12)  # a gap is a negative indentation
    assert report["energy_balance_error"] < 2e-4


def test_a_damped_run_settles_on_the_equilibrium_solve():
    settled = analysed(block_against_a_stop(simulate={"until": 3.0, "step": 1e-3, "damping": 20.0}), "simulate")
    static = analysed(block_against_a_stop(), "equilibrium")
    force = static["outputs"]["contacts.touch.normal_force"]
    assert settled["outputs"]["contacts.touch.normal_force"][-1] == pytest.approx(force, rel=1e-6)


def test_a_compliant_rod_bent_against_a_stop_settles_on_the_equilibrium_solve():
    """The Table 4.1 rod (8 cubic elements, shear and axial strain, its steel's density) pushed
    up by 3 N at its tip, a stop 0.15 m above the tip's pad (K = 1e6 N/m^1.5): with
    mass-proportional damping the tip comes to rest on the stop with the equilibrium solve's
    contact force (to 1e-6; 3.9e-8 measured)."""
    doc = json.loads((EXAMPLES / "rod_free_vibration.json").read_text())
    doc["loads"]["hold"]["force"] = [0.0, 3.0]
    doc["contacts"] = {
        "sites": {"pad": {"type": "circle", "body": "tip", "centre": [0, 0], "radius": 0.01}},
        "objects": {"stop": {"type": "half_plane", "point": [1.11, 0.15], "normal": [0, -1]}},
        "pairs": {
            "touch": {"site": "pad", "object": "stop", "normal": {"law": "hertz", "stiffness": 1e6, "exponent": 1.5}}
        },
    }
    doc["simulate"] = {"until": 4.0, "step": 1e-3, "damping": 40.0}
    static = analysed(doc, "equilibrium")
    force = static["outputs"]["contacts.touch.normal_force"]
    assert 0.5 < force < 3.0  # the stop takes part of the push
    settled = analysed(doc, "simulate")
    forces = np.array(settled["outputs"]["contacts.touch.normal_force"])
    assert forces.max() > 2 * force  # it struck the stop first
    assert forces[-1] == pytest.approx(force, rel=1e-6)


@pytest.mark.parametrize(
    "change, pointer, problem",
    [
        (
            {"normal": {"law": "lna_esdu", "length": 0.01, "materials": ["steel", "steel"]}},
            "/contacts/pairs/touch/normal/law",
            "a newmark or generalized_alpha simulation (and the equilibrium solve) does not take the normal law "
            "'lna_esdu' (it is for an event_driven simulation); it takes hertz or hunt_crossley or lankarani_nikravesh or "
            "flores",
        ),
        (
            {"normal": {"law": "hertz", "stiffness": {"contact": "spheres", "materials": ["steel", "steel"]}}},
            "/contacts/pairs/touch/normal/stiffness",
            "a newmark or generalized_alpha simulation takes the hertz law's stiffness K as a number (force / "
            "length^exponent in the document's units), not computed from the materials",
        ),
        (
            {"friction": 0.3},
            "/contacts/pairs/touch/friction",
            'a newmark or generalized_alpha simulation takes a regularized friction law of the slip speed ({"law": '
            '"ambrosio", "sliding": f_d, "v0": ..., "v1": ...}), not Coulomb\'s coefficient: give the law, or 0',
        ),
        (
            {"friction": {"law": "coulomb", "sliding": 0.3}},
            "/contacts/pairs/touch/friction/law",
            "a newmark or generalized_alpha simulation (and the equilibrium solve) does not take the friction law 'coulomb' "
            "(it is for a quasi-static contact solve, a moreau simulation); it takes none or ambrosio",
        ),
        (
            {"friction": {"law": "ambrosio", "sliding": 0.3, "v0": 0.01, "v1": 0.01}},
            "/contacts/pairs/touch/friction/v1",
            "must exceed v0 (0.01 m/s): the law ramps the friction up between them",
        ),
    ],
)
def test_link_dynamics_refuses_a_pair_it_does_not_model(change, pointer, problem):
    doc = block_against_a_stop(simulate={"until": 0.1})
    doc["contacts"]["pairs"]["touch"].update(change)
    with pytest.raises(MechanismError) as caught:
        analysed(doc, "simulate")
    assert (caught.value.pointer, caught.value.problem) == (pointer, problem)


def test_link_dynamics_refuses_a_jaw_site_and_the_equilibrium_solve_leaves_it_to_the_contact_solve():
    doc = block_against_a_stop(simulate={"until": 0.1})
    doc["contacts"]["sites"]["pad"] = {"type": "jaw", "body": "block", "vertices": [[0, 0], [0.02, 0], [0, 0.02]]}
    with pytest.raises(MechanismError) as caught:
        analysed(doc, "simulate")
    assert (caught.value.pointer, caught.value.problem) == (
        "/contacts/pairs/touch/site",
        "a newmark or generalized_alpha simulation takes a pair's site as a circle on a "
        "body (a pin, a roller, a pad); 'pad' is a jaw",
    )
    assert "contacts.touch.normal_force" not in analysed(doc, "equilibrium")["outputs"]
