"""Networks of links (seed 002 Ch. 5): joints as zero-size bodies, pinned and clamped ends,
links with rigid bodies and curved beams in one mechanism, and bad networks."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from elastica_oracles import cantilever_tip

from flexmech import models
from flexmech.models import MechanismError
from flexmech.service.solvers.equilibrium import NewtonOptions, solve_equilibrium

TIGHT = NewtonOptions(tol_residual=1e-13, tol_step=1e-12)
SI = {"length": "m", "force": "N", "stress": "Pa", "angle": "rad"}


def network(bodies: dict, links: dict, loads: dict, *, E=2e11, b=0.01, h=0.002) -> dict:
    elements = {}
    for name, spec in links.items():
        element = {"type": "link", "material": "steel", "section": "strip"}
        element.update(spec)
        elements[name] = element
    return {
        "name": "network",
        "units": SI,
        "materials": {"steel": {"E": E}},
        "sections": {"strip": {"b": b, "h": h}},
        "bodies": bodies,
        "elements": elements,
        "loads": loads,
    }


def solve(document, options=TIGHT):
    mech = models.compile_mechanism(models.load_document(document))
    result = solve_equilibrium(mech, options)
    assert result.converged, result.message
    return mech, result.outputs()


def test_a_cantilever_split_at_a_clamped_floating_joint_is_still_the_elastica():
    """Two links clamped to a floating joint (Eqs. 5.2-5.3) behave as one link."""
    EI, L, F = 0.08, 0.1016, 15.0
    document = {
        "name": "split cantilever",
        "units": SI,
        "materials": {"m": {"E": EI / 1e-9}},
        "sections": {"s": {"shape": "general", "I": 1e-9}},
        "bodies": {
            "ground": {"fixed": True, "position": [0, 0]},
            "J": {"joint": True, "position": [0.4 * L, 0]},
            "tip": {"joint": True, "position": [L, 0]},
        },
        "elements": {
            "L1": {"type": "link", "from": "ground", "to": "J", "length": 0.4 * L, "material": "m", "section": "s"},
            # the second link runs backwards (u from the tip to the joint)
            "L2": {
                "type": "link",
                "from": "tip",
                "to": "J",
                "length": 0.6 * L,
                "material": "m",
                "section": "s",
                "shape": {"type": "straight", "angle": math.pi},
            },
        },
        "loads": {"F": {"type": "force", "body": "tip", "force": [0, F]}},
    }
    _, out = solve(document)
    x, y, rotation = cantilever_tip(EI, L, F)
    assert out["bodies.tip.x"] == pytest.approx(x, rel=1e-9)
    assert out["bodies.tip.y"] == pytest.approx(y, rel=1e-9)
    assert out["bodies.tip.angle"] == pytest.approx(rotation, rel=1e-9)
    # L2 runs from the tip, so its internal force is the reaction on the load: (h, v) = -F ey.
    assert out["elements.L2.v"] == pytest.approx(-F, rel=1e-12)
    assert out["elements.L1.v"] == pytest.approx(F, rel=1e-12)


def test_a_pinned_star_matches_the_linear_truss():
    """Three pinned, axially elastic links meet at one floating pin joint; for a small load
    the joint moves by K^-1 P with K = sum EA/L n n^T (a truss)."""
    E, b, h = 2e11, 0.01, 0.002
    EA = E * b * h
    grounds = {"A": [0.0, 0.0], "B": [1.0, 0.0], "C": [0.2, 1.2]}
    joint = np.array([0.5, 0.4])
    bodies = {name: {"fixed": True, "position": xy} for name, xy in grounds.items()}
    bodies["J"] = {"joint": True, "position": list(joint)}
    links, K = {}, np.zeros((2, 2))
    for name, xy in grounds.items():
        d = joint - np.array(xy)
        length = float(np.hypot(*d))
        n = d / length
        K += EA / length * np.outer(n, n)
        links[f"to_{name}"] = {
            "from": name,
            "to": "J",
            "length": length,
            "start": "pinned",
            "end": "pinned",
            "axial": True,
            "shape": {"type": "straight", "angle": math.atan2(d[1], d[0])},
        }
    P = np.array([30.0, -50.0])  # N: strains ~1e-5, so the truss is linear to ~1e-5
    mech, out = solve(network(bodies, links, {"P": {"type": "force", "body": "J", "force": list(P)}}))
    assert "J.angle" not in mech.free_coordinates  # a pin joint has no rotation
    moved = np.array([out["bodies.J.x"], out["bodies.J.y"]]) - joint
    assert moved == pytest.approx(np.linalg.solve(K, P), rel=1e-4)
    # Pinned at both ends, each link carries only an axial force: no end moments.
    for name in links:
        assert abs(out[f"elements.{name}.M_start"]) < 1e-9 and abs(out[f"elements.{name}.M_end"]) < 1e-9


def test_the_exact_curved_beam_equals_a_link_with_the_same_arc(gripper_dict):
    """Links, rigid bodies and curved beams in one mechanism: replacing one exact curved beam
    of the gripper by a `link` with the same arc changes nothing."""
    exact = copy.deepcopy(gripper_dict)
    for element in exact["elements"].values():
        element["model"] = "exact"
    mixed = copy.deepcopy(exact)
    beam = mixed["elements"]["a"]
    ccw = beam.get("direction", "ccw") == "ccw"
    start_body, end_body = (beam["from"], beam["to"]) if ccw else (beam["to"], beam["from"])
    arc = float(beam["arc_angle"])
    start = float(beam["start_angle"]) - (0 if ccw else arc)
    radius = float(beam["radius"])
    center = [float(c) for c in beam["center"]]
    mixed["elements"]["a"] = {
        "type": "link",
        "from": start_body,
        "to": end_body,
        "material": beam["material"],
        "section": beam["section"],
        "at": [center[0] + radius * math.cos(math.radians(start)), center[1] + radius * math.sin(math.radians(start))],
        "length": radius * math.radians(arc),
        "shape": {"type": "arc", "angle": start + 90, "sweep": arc},
    }
    _, out_exact = solve(exact, NewtonOptions())
    _, out_mixed = solve(mixed, NewtonOptions())
    for name in ("end_effector.x", "end_effector.y", "bodies.input.y"):
        assert out_mixed[name] == pytest.approx(out_exact[name], rel=1e-9, abs=1e-12)


def test_a_floating_joint_with_no_path_to_ground_is_named():
    bodies = {
        "A": {"fixed": True, "position": [0, 0]},
        "J": {"joint": True, "position": [1, 0]},
        "K": {"joint": True, "position": [3, 0]},
        "M": {"joint": True, "position": [4, 0]},
    }
    links = {"L1": {"from": "A", "to": "J", "length": 1.0}, "L2": {"from": "K", "to": "M", "length": 1.0}}
    with pytest.raises(MechanismError) as info:
        models.compile_mechanism(models.load_document(network(bodies, links, {})))
    assert str(info.value) == (
        "/bodies/K: floating joint 'K' has no path to a fixed body through elements or "
        "impact pairs: connect it to ground by a link or a flexure, or fix it"
    )


def test_a_body_held_only_by_pins_must_be_a_joint():
    """A rigid body on pins alone is free to spin: the solver names the motion."""
    bodies = {
        "A": {"fixed": True, "position": [0, 0]},
        "B": {"fixed": True, "position": [2, 0]},
        "J": {"position": [1, 0]},
    }
    links = {
        "L1": {"from": "A", "to": "J", "length": 1.0, "end": "pinned"},
        "L2": {"from": "J", "to": "B", "length": 1.0, "start": "pinned"},
    }
    mech = models.compile_mechanism(models.load_document(network(bodies, links, {})))
    with pytest.raises(MechanismError, match="nothing resists a motion of J.angle"):
        solve_equilibrium(mech)


def test_an_undetermined_force_is_named_when_no_body_moves():
    """An inextensible straight link between two fixed bodies: no body can move, but its axial
    force is not determined (the distance is held twice). The message names the unknown, not
    an empty list of moving coordinates."""
    bodies = {"A": {"fixed": True, "position": [0, 0]}, "B": {"fixed": True, "position": [1, 0]}}
    mech = models.compile_mechanism(
        models.load_document(network(bodies, {"L1": {"from": "A", "to": "B", "length": 1.0}}, {}))
    )
    with pytest.raises(MechanismError) as info:
        solve_equilibrium(mech)
    assert info.value.pointer == "/elements"
    assert "every body is held: the elements' unknowns L1.h are not determined" in info.value.problem
    stretchy = network(bodies, {"L1": {"from": "A", "to": "B", "length": 1.0, "axial": True}}, {})
    assert solve_equilibrium(models.compile_mechanism(models.load_document(stretchy))).converged


def test_a_moment_on_a_pin_joint_is_refused():
    bodies = {"A": {"fixed": True, "position": [0, 0]}, "J": {"joint": True, "position": [1, 0]}}
    links = {"L1": {"from": "A", "to": "J", "length": 1.0, "end": "pinned"}}
    with pytest.raises(MechanismError) as info:
        models.compile_mechanism(
            models.load_document(network(bodies, links, {"M": {"type": "moment", "body": "J", "moment": 1.0}}))
        )
    assert str(info.value) == (
        "/loads/M: joint 'J' is held only by pins, so it cannot take a moment: apply forces at the joint itself"
    )


@pytest.mark.parametrize(
    "change, pointer, message",
    [
        (lambda e: e.update(length=0), "/elements/L1/length", "must be positive, got 0 (SI)"),
        (
            lambda e: e.update(shape={"type": "expression", "expression": "__import__('os').system('true')"}),
            "/elements/L1/shape/expression",
            "unsafe or unsupported expression: a call of a computed function is not allowed",
        ),
        (
            lambda e: e.update(shape={"type": "expression", "expression": "__import__('os')"}),
            "/elements/L1/shape/expression",
            "unsafe or unsupported expression: a call of '__import__' is not allowed",
        ),
        (
            lambda e: e.update(shape={"type": "expression", "expression": "u.__class__"}),
            "/elements/L1/shape/expression",
            "unsafe or unsupported expression: an Attribute expression is not allowed",
        ),
        (
            lambda e: e.update(shape={"type": "expression", "expression": "0.3 * sin(2 * pi * u"}),
            "/elements/L1/shape/expression",
            "cannot parse expression '0.3 * sin(2 * pi * u': '(' was never closed",
        ),
        (
            lambda e: e.update(shape={"type": "expression", "expression": "x + 1"}),
            "/elements/L1/shape/expression",
            "unsafe or unsupported expression: the name 'x' is not allowed",
        ),
        (
            lambda e: e.update(shape={"type": "expression", "expression": "-" * 1900 + "u"}),
            "/elements/L1/shape/expression",
            "expression nested too deeply",
        ),
        (lambda e: e.update(order=5), "/elements/L1/order", "the integration order must be even, got 5"),
        (
            lambda e: e.update(shear=True),
            "/materials/steel/G",
            "a link with shear needs the shear modulus G or Poisson's ratio nu",
        ),
    ],
)
def test_bad_links_are_named(change, pointer, message):
    bodies = {"A": {"fixed": True, "position": [0, 0]}, "J": {"joint": True, "position": [1, 0]}}
    document = network(bodies, {"L1": {"from": "A", "to": "J", "length": 1.0}}, {})
    change(document["elements"]["L1"])
    with pytest.raises(MechanismError) as info:
        models.compile_mechanism(models.load_document(document))
    assert info.value.pointer == pointer
    assert info.value.problem.startswith(message), info.value.problem


def test_expressions_are_built_not_evaluated():
    """The expression shape equals the same function given as a polynomial."""
    bodies = {"A": {"fixed": True, "position": [0, 0]}, "J": {"joint": True, "position": [1, 0]}}
    load = {"P": {"type": "force", "body": "J", "force": [0.0, 2.0]}}
    as_text = network(
        bodies,
        {
            "L1": {
                "from": "A",
                "to": "J",
                "length": 1.0,
                "shape": {"type": "expression", "expression": "0.2 - 0.5*u + 0.3*u**2"},
            }
        },
        load,
    )
    as_polynomial = network(
        bodies,
        {
            "L1": {
                "from": "A",
                "to": "J",
                "length": 1.0,
                "shape": {"type": "polynomial", "coefficients": [0.2, -0.5, 0.3]},
            }
        },
        load,
    )
    _, a = solve(as_text)
    _, b = solve(as_polynomial)
    assert a["elements.L1.x_end"] == pytest.approx(b["elements.L1.x_end"], rel=1e-14)
    assert a["elements.L1.angle_end"] == pytest.approx(b["elements.L1.angle_end"], rel=1e-14)


def test_a_rigid_body_with_offset_attachment_and_load_point_rotates_consistently():
    """The tip body's reference point sits off the beam; the link attaches to it at the beam's
    end and the load acts at that same material point. Arms rotate with the body, so the
    beam still sees a plain dead tip force: the elliptic-integral cantilever."""
    EI, L, F = 0.08, 0.1016, 15.0
    document = {
        "name": "offset tip body",
        "units": SI,
        "materials": {"m": {"E": EI / 1e-9}},
        "sections": {"s": {"shape": "general", "I": 1e-9}},
        "bodies": {"ground": {"fixed": True, "position": [0, 0]}, "tip": {"position": [L + 0.03, -0.02], "angle": 0.4}},
        "elements": {
            "beam": {"type": "link", "from": "ground", "to": "tip", "length": L, "material": "m", "section": "s"}
        },
        "loads": {"F": {"type": "force", "body": "tip", "at": [L, 0], "force": [0, F]}},
        "outputs": {"end": {"type": "point", "body": "tip", "at": [L, 0]}},
    }
    _, out = solve(document)
    x, y, rotation = cantilever_tip(EI, L, F)
    assert out["end.x"] == pytest.approx(x, rel=1e-9)
    assert out["end.y"] == pytest.approx(y, rel=1e-9)
    assert out["bodies.tip.angle"] - 0.4 == pytest.approx(rotation, rel=1e-9)
