"""Bad input is named by its JSON pointer and explained; non-convergence is a status."""

from __future__ import annotations

import copy
import json

import pytest
from conftest import ACTUATION

from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service import NewtonOptions, solve_equilibrium


def compile_modified(gripper_dict, edit):
    doc = copy.deepcopy(gripper_dict)
    edit(doc)
    return compile_mechanism(load_document(doc))


def expect_error(gripper_dict, edit, pointer, *phrases):
    with pytest.raises(MechanismError) as info:
        compile_modified(gripper_dict, edit)
    assert info.value.pointer == pointer
    for phrase in phrases:
        assert phrase in str(info.value)
    assert str(info.value).startswith(pointer + ": ")
    return info.value


def test_unknown_body_is_named(gripper_dict):
    err = expect_error(
        gripper_dict, lambda d: d["elements"]["c"].update(to="folower"), "/elements/c/to", "unknown body 'folower'"
    )
    assert "follower" in err.problem  # the message lists the bodies that exist


def test_load_on_unknown_body(gripper_dict):
    expect_error(
        gripper_dict,
        lambda d: d["loads"]["actuation"].update(body="nobody"),
        "/loads/actuation/body",
        "unknown body 'nobody'",
    )


@pytest.mark.parametrize("radius", [0.0, -0.2, "-200 um"])
def test_non_positive_radius(gripper_dict, radius):
    expect_error(
        gripper_dict, lambda d: d["elements"]["b"].update(radius=radius), "/elements/b/radius", "must be positive"
    )


@pytest.mark.parametrize("field, value", [("h", 0), ("b", "-25 um")])
def test_non_positive_section(gripper_dict, field, value):
    expect_error(
        gripper_dict,
        lambda d: d["sections"]["flexure"].update({field: value}),
        f"/sections/flexure/{field}",
        "must be positive",
    )


@pytest.mark.parametrize("angle", [0, 360, 400, -30, "7 rad"])
def test_arc_angle_outside_0_360(gripper_dict, angle):
    expect_error(
        gripper_dict,
        lambda d: d["elements"]["a"].update(arc_angle=angle),
        "/elements/a/arc_angle",
        "arc angle must lie in (0, 360) deg",
    )


def test_no_fixed_body(gripper_dict):
    expect_error(gripper_dict, lambda d: d["bodies"]["frame"].update(fixed=False), "/bodies", "no fixed body")


def test_a_body_with_no_path_to_ground_is_named(gripper_dict):
    def add_loose_body(d):
        d["bodies"]["loose"] = {"position": [3.0, 3.0]}

    with pytest.raises(MechanismError) as info:
        compile_modified(gripper_dict, add_loose_body)
    assert info.value.pointer == "/bodies/loose"
    assert "floating body 'loose' has no path to a fixed body through elements" in info.value.problem


def test_under_constrained_by_missing_flexure(gripper_dict):
    mech = compile_modified(gripper_dict, lambda d: d["elements"].pop("d"))
    # without flexure d the follower hangs on c alone: still stiff; remove c too and it is free
    solve_equilibrium(mech)
    with pytest.raises(MechanismError, match="floating body 'follower' has no path to a fixed body"):
        compile_modified(gripper_dict, lambda d: (d["elements"].pop("d"), d["elements"].pop("c")))


def test_unit_of_the_wrong_kind(gripper_dict):
    expect_error(
        gripper_dict, lambda d: d["sections"]["flexure"].update(h="5 uN"), "/sections/flexure/h", "is not a length"
    )


def test_unreadable_quantity(gripper_dict):
    expect_error(
        gripper_dict, lambda d: d["sections"]["flexure"].update(h="five microns"), "/sections/flexure/h", "cannot read"
    )


def test_schema_violations_name_the_field(gripper_dict):
    expect_error(
        gripper_dict, lambda d: d["elements"]["a"].pop("radius"), "/elements/a/radius", "required field is missing"
    )
    expect_error(gripper_dict, lambda d: d["elements"]["a"].update(radious=0.2), "/elements/a/radious", "unknown field")
    expect_error(
        gripper_dict,
        lambda d: d["elements"]["a"].update(type="hinge"),
        "/elements/a/type",
        "unknown type 'hinge' (types: curved_beam, link, spring, pin, slider)",
    )
    expect_error(
        gripper_dict,
        lambda d: d["elements"]["a"].update(type="curved_bem"),
        "/elements/a/type",
        "unknown type 'curved_bem' (did you mean 'curved_beam'? types: ",
    )
    expect_error(
        gripper_dict, lambda d: d["elements"]["a"].pop("type"), "/elements/a/type", "required field is missing"
    )
    expect_error(
        gripper_dict,
        lambda d: d["loads"]["actuation"].update(force=[1.0]),
        "/loads/actuation/force/1",
        "required field is missing",
    )
    expect_error(gripper_dict, lambda d: d["materials"]["silicon"].update(E=[100]), "/materials/silicon/E", "")
    expect_error(
        gripper_dict,
        lambda d: d["loads"]["actuation"].update(at=[0, 0], offset=[0, 0]),
        "/loads/actuation",
        "either 'at' or 'offset'",
    )


def test_not_json(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('{"bodies": {')
    with pytest.raises(MechanismError, match="is not valid JSON"):
        load_document(path)


def test_override_of_a_field_that_does_not_exist(gripper_pnl):
    with pytest.raises(MechanismError) as info:
        gripper_pnl.with_values({"/loads/actuation/force/7": 1.0})
    assert info.value.pointer == "/loads/actuation/force/7"
    assert "not a numeric field" in info.value.problem


def test_override_is_checked_like_the_document(gripper_pnl):
    with pytest.raises(MechanismError, match="/sections/flexure/h: must be positive"):
        gripper_pnl.with_values({"/sections/flexure/h": -1.0})


def test_load_beyond_convergence_is_a_status(gripper_pnl):
    result = solve_equilibrium(gripper_pnl.with_values({ACTUATION: 1e4}), NewtonOptions(max_iterations=40))
    assert result.status == "not_converged"
    assert result.iterations == 40
    assert result.residual_norm_force > 1.0  # uN: far from balanced
    summary = result.summary()
    assert summary["status"] == "not_converged"
    assert summary["iterations"] == 40
    assert summary["residual_unit"] == "uN"
    assert "no convergence in 40 iterations" in summary["message"]
    json.dumps({k: v for k, v in summary.items() if k != "outputs"})


def test_unknown_solver_options_fail_loudly():
    with pytest.raises(ValueError, match="jacobian: unknown choice 'exact'"):
        NewtonOptions(jacobian="exact")


def test_rotation_beyond_the_models_range_is_flagged(gripper_pnl):
    inside = solve_equilibrium(gripper_pnl.with_values({ACTUATION: 10.0}))
    assert inside.warnings() == []
    beyond = solve_equilibrium(gripper_pnl.with_values({ACTUATION: 300.0}))
    assert beyond.converged
    assert any("hold to about 20 deg" in w for w in beyond.warnings())
