"""The public Python surface (issue 48): `import flexmech` names what it offers and nothing heavy
until asked; a mechanism from a file, a dict or an example's name; fields by pointer, keyword or
quantity; results as tables with units in a terminal and in Jupyter, a document's names escaped."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from conftest import EXAMPLES

import flexmech

FORCE = "/loads/actuation/force/1"


@pytest.fixture(scope="module")
def gripper():
    return flexmech.load("gripper", model="partial_nonlinear")


def test_import_flexmech_loads_no_physics_until_asked():
    script = (
        "import sys, flexmech; print(flexmech.__version__); "
        "print(sorted(m for m in ('casadi', 'numpy', 'fastapi', 'flexmech.models') if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    version, loaded = done.stdout.split("\n")[:2]
    assert done.returncode == 0 and version and version != "unknown" and loaded == "[]", done.stderr
    assert set(flexmech.__all__) >= {"load", "solve", "solve_for_target", "sweep", "modes", "simulate", "Client"}
    with pytest.raises(AttributeError, match="no attribute 'solve_equilibrium'"):
        flexmech.solve_equilibrium  # noqa: B018 (a private name is not offered)


def test_a_mechanism_from_a_file_a_dict_or_an_examples_name_is_the_same(gripper):
    from_file = flexmech.load(EXAMPLES / "gripper.json", model="partial_nonlinear")
    from_dict = flexmech.load(json.loads((EXAMPLES / "gripper.json").read_text()), model="partial_nonlinear")
    values = [
        flexmech.solve(m, actuation_force_y=40).outputs["end_effector.x"] for m in (gripper, from_file, from_dict)
    ]
    assert values[0] == values[1] == values[2]
    with pytest.raises(flexmech.MechanismError, match="no file 'gripperz' and no example of that name"):
        flexmech.load("gripperz")


def test_fields_by_pointer_keyword_or_quantity_give_one_equilibrium(gripper):
    by_pointer = flexmech.solve(gripper, {FORCE: 40})
    by_keyword = flexmech.solve(gripper, actuation_force_y=40)
    by_quantity = flexmech.solve(gripper, {FORCE: "0.04 mN"})
    assert by_pointer.outputs == by_keyword.outputs
    assert by_quantity.outputs["end_effector.x"] == pytest.approx(by_pointer.outputs["end_effector.x"], rel=1e-12)
    with pytest.raises(flexmech.MechanismError, match="no numeric field is named actuation_y"):
        flexmech.solve(gripper, actuation_y=40)


def test_results_print_as_tables_with_units_and_escape_names():
    document = json.loads((EXAMPLES / "gripper.json").read_text())
    document["outputs"]["<b>tip<b>"] = document["outputs"]["end_effector"]
    result = flexmech.solve(flexmech.load(document), actuation_force_y=50)
    text, page = repr(result), result._repr_html_()
    assert "<b>tip<b>.x" in text and " mm" in text and "converged after" in text
    assert "&lt;b&gt;tip&lt;b&gt;.x" in page and "<b>tip" not in page and "<td>mm</td>" in page
    target = flexmech.solve_for_target(flexmech.load(document), FORCE, "end_effector.x", 0.0)
    assert target.unit == "uN" and "uN" in repr(target) and "<table>" in target._repr_html_()
