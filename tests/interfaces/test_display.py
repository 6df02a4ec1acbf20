"""How numbers are shown (service.display, issue 49): the display unit of a quantity from the
document's unit and the result's magnitudes, energies in joules, six significant digits, and
round-off below a quantity's noise floor as 0 (residuals shown exactly)."""

from __future__ import annotations

import pytest

from flexmech.service.display import Display, display, displays, exact


@pytest.mark.parametrize(
    ("unit", "values", "kind", "shown_unit", "texts"),
    [
        ("GPa", [0.00146703, -0.00121], "stress", "MPa", ["1.46703", "-1.21"]),  # the gripper's stresses
        ("kg", [1.21946e-09, 6.19788e-12], "mass", "ug", ["1.21946", "0.00619788"]),
        ("kg", [6.19788e-12], "mass", "ng", ["6.19788"]),
        ("uN*mm", [4.77266, 67.0139], "energy", "nJ", ["4.77266", "67.0139"]),  # 1 uN*mm is 1 nJ
        ("N*m", [4.77e-12], "energy", "pJ", ["4.77"]),
        ("uN*mm", [4.77266, 67.0139], "moment", "uN*mm", ["4.77266", "67.0139"]),  # in range: the document's
        ("mm", [-6.92779e-15, 3.34142, 0.149159], "length", "mm", ["0", "3.34142", "0.149159"]),  # round-off: 0
        ("m/N", [-1.57772e-30, 0.0032], None, "mm/N", ["0", "3.2"]),
        ("Hz", [2200.03, 7077.55], "frequency", "Hz", ["2200.03", "7077.55"]),
        ("Pa", [2.1e11], "stress", "GPa", ["210"]),
        ("deg", [1e-5, 0.002], "angle", "deg", ["1e-05", "0.002"]),  # a degree takes no prefix
    ],
)
def test_a_quantity_is_shown_in_its_display_unit(unit, values, kind, shown_unit, texts):
    shown = display(unit, values, kind)
    assert shown.unit == shown_unit
    assert [shown.text(v) for v in values] == texts


def test_the_noise_floor_is_relative_to_the_largest_of_the_kind_and_keeps_what_is_a_result():
    shown = display("mm", [1e-9, 1.0])
    assert shown.text(1e-9) == "1e-09" and shown.text(1e-11) == "0"  # 1e-9 of the largest is a result
    tiny = display("mm", [1e-20, 2e-20])  # every value tiny: the largest sets the floor, nothing is noise
    assert tiny.unit != "mm" and tiny.text(2e-20) != "0"
    assert Display("mm").text(None) == "-" and Display("mm").text(float("nan")) == "-"


def test_names_sharing_a_unit_share_a_display_chosen_from_all_their_values():
    values = {"a.stress": 0.0012, "b.stress": 0.0003, "tip.x": 3.3}
    units = {"a.stress": "GPa", "b.stress": "GPa", "tip.x": "mm"}
    chosen = displays(values, units)
    assert chosen["a.stress"] is chosen["b.stress"] and chosen["a.stress"].unit == "MPa"
    assert chosen["b.stress"].text(values["b.stress"]) == "0.3" and chosen["tip.x"].unit == "mm"


def test_a_residual_is_shown_exactly_with_its_unit():
    assert exact(1.4456028966473384e-14, "uN*mm") == "1.446e-14 uN*mm"
    assert exact(None) == "-"


def test_a_plotted_quantity_is_on_the_axis_the_tables_use():
    """on_axis: 0.19 GPa stresses on an MPa axis, scaled; a point left out (NaN) stays out;
    round-off beside them is 0; energies in J."""
    import numpy as np

    from flexmech.service.display import on_axis

    unit, (first, second) = on_axis("GPa", [np.array([0.188765, np.nan]), np.array([1.46703e-3, 3e-17])])
    assert unit == "MPa"
    assert first[0] == 188.765 and np.isnan(first[1])
    assert second.tolist() == [1.46703, 0.0]
    unit, (energy,) = on_axis("uN*mm", [np.array([4.77266, 1.0])], "energy")
    assert unit == "nJ" and energy.tolist() == [4.77266, 1.0]
