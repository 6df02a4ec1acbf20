"""Element families in impact simulations (models.impacts.families, through each
family's impact hooks): a pin in its hole riding a slider meets the hole at the time and
speed of a fall along the slider, held by the slider's normal force alone; an element
without a finite stiffness at its end is refused, saying why."""

from __future__ import annotations

import math

import numpy as np
import pytest
from impact_cases import csfh, parsed

from flexmech.service.impacts.run import run_impacts

G, MASS, CLEARANCE = 9.81, 10.0, 0.02
ANGLE = 60.0  # deg: the slider's axis from the x axis, through the hole's centre


@pytest.mark.parametrize("scheme", ["event_driven", "moreau"])
def test_a_pin_on_a_slider_falls_along_it_into_its_hole(scheme):
    """Released at the hole's centre, the body slides down the axis with g sin(60 deg) and
    meets the hole after sqrt(2 c / (g sin)) at sqrt(2 g sin c); until then the slider pushes
    across its axis with m g cos(60 deg) and no couple, and the body never turns."""
    doc = csfh("6.1", scheme=scheme, until=0.15, step=1e-5 if scheme == "moreau" else 1e-4)
    doc["simulate"]["initial"]["hinge"] = {"displacement": [0, 0, 0]}
    doc["elements"] = {"rail": {"type": "slider", "from": "frame", "to": "hinge", "angle": ANGLE}}
    report = run_impacts(*parsed(doc))[1]
    along = G * math.sin(math.radians(ANGLE))
    first = report["impacts"][0]
    fall = math.sqrt(2 * CLEARANCE / along)
    if scheme == "event_driven":
        assert first["time"] == pytest.approx(fall, rel=1e-8)
        assert first["impact_speed"] == pytest.approx(math.sqrt(2 * along * CLEARANCE), rel=1e-8)
    else:
        assert abs(first["time"] - fall) <= 1e-5  # within a step
    times = np.array(report["times"])
    before = (times > 0.01) & (times < first["time"] - 1e-3)
    rail = report["joints"]["rail"]
    np.testing.assert_allclose(np.array(rail["N"])[before], MASS * G * math.cos(math.radians(ANGLE)), rtol=1e-6)
    assert np.abs(np.array(rail["M"])[before]).max() < 1e-6
    assert np.abs(report["coordinates"]["hinge.theta"]).max() < 1e-9
    x, y = (np.array(report["coordinates"][f"hinge.{c}"]) for c in "xy")
    np.testing.assert_allclose(y, x * math.tan(math.radians(ANGLE)), atol=1e-9)  # on the axis throughout


def test_an_element_without_a_finite_stiffness_at_its_end_is_refused_saying_why():
    """An element with unknowns of its own enters an impact model by its statics stiffness at
    its end (models.impacts.condensed): an inextensible straight link has none along itself
    (refused, saying so); given axial strain, the same link runs."""
    from flexmech.models import MechanismError

    doc = csfh("6.1", until=0.01)
    doc["materials"]["steel"] = {"E": 210, "nu": 0.3}
    doc["sections"] = {"strip": {"b": 0.01, "h": 0.001}}
    doc["elements"] = {
        "arm": {"type": "link", "from": "frame", "to": "hinge", "length": 0.1, "material": "steel", "section": "strip"}
    }
    with pytest.raises(MechanismError) as caught:
        run_impacts(*parsed(doc))
    assert caught.value.pointer == "/elements/arm/type"
    assert caught.value.problem == (
        "the element's stiffness at body 'hinge' is not finite and positive in every "
        "direction, and an impact simulation takes an element by that stiffness: an "
        'inextensible straight link is rigid along itself (give it "axial": true), a '
        "pinned end leaves its body free to turn (clamp it)"
    )
    doc["elements"]["arm"]["axial"] = True
    assert run_impacts(*parsed(doc))[1]["status"] == "finished"
