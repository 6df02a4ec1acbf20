"""Seed 004's conjugate-surface flexure hinge with its flexure written as a `link` (an arc of
the same centre, radius and sweep) in impact simulations (models.impacts.condensed): the link's
own statics stiffness about the drawn state, condensed onto the hinge at the link's end.

An Euler-Bernoulli link (no shear, no axial strain) has the closed-form stiffness of the
curved beam (seed 000, Eq. 2), so its run reproduces the curved-beam run; with shear and axial
strain it is a little softer (5.4e-4 of the largest entry), and the runs stay close."""

from __future__ import annotations

import math

import numpy as np
import pytest
from impact_cases import csfh, parsed

from flexmech.service.impacts.run import run_impacts
from flexmech.service.impacts.study import variant

ARC = 0.144 * math.radians(300)  # the example's flexure: radius 0.144 m, 300 deg from angle 0 about (0.22, 0.1)


def as_link(doc: dict, **fields) -> dict:
    doc["elements"]["flexure"] = {
        "type": "link",
        "from": "frame",
        "to": "hinge",
        "at": [0.364, 0.1],
        "length": ARC,
        "shape": {"type": "arc", "angle": 90, "sweep": 300},
        "material": "hinge",
        "section": "flexure",
        **fields,
    }
    return doc


def end_state(report: dict) -> np.ndarray:
    return np.array([values[-1] for part in ("coordinates", "velocities") for values in report[part].values()])


def impact_times(report: dict) -> list[float]:
    return [impact["time"] for impact in report["impacts"][:3]]


@pytest.mark.parametrize("stiffness", ["constant", "turning"])
@pytest.mark.parametrize("scheme", ["event_driven", "moreau"])
def test_an_euler_bernoulli_link_reproduces_the_curved_beam_run(scheme, stiffness):
    fields = {"scheme": scheme, "until": 0.5, "flexure_stiffness": stiffness}
    if scheme == "moreau":
        fields["step"] = 1e-5
    beam = run_impacts(*parsed(csfh("6.3", **fields)))[1]
    link = run_impacts(*parsed(as_link(csfh("6.3", **fields))))[1]
    assert len(beam["impacts"]) >= 3
    np.testing.assert_allclose(impact_times(link), impact_times(beam), rtol=1e-8)
    np.testing.assert_allclose(end_state(link), end_state(beam), rtol=1e-6, atol=1e-6 * np.abs(end_state(beam)).max())


def test_shear_and_axial_strain_soften_the_flexure_a_little():
    """The first impact comes later by a few 1e-5 of its time, and the state at 0.5 s (after
    seven impacts) stays within 2 % of the Euler-Bernoulli run's largest component."""
    beam = run_impacts(*parsed(csfh("6.3", until=0.5)))[1]
    link = run_impacts(*parsed(as_link(csfh("6.3", until=0.5), shear=True, axial=True)))[1]
    first, first_link = beam["impacts"][0]["time"], link["impacts"][0]["time"]
    assert 0 < first_link - first < 1e-4 * first
    difference = np.abs(end_state(link) - end_state(beam)).max()
    assert 0 < difference < 0.02 * np.abs(end_state(beam)).max()


def test_the_state_derivative_in_the_links_modulus_equals_central_differences():
    """The condensed stiffness is a computed block of the run's parameters, differentiated
    exactly: d(state at 0.1 s, after the first impact)/dE of the link, against the runs with E
    moved by 1e-5 of itself."""
    pointer = "/materials/hinge/E"
    doc = as_link(csfh("6.3", until=0.1), shear=True, axial=True)
    doc["contacts"]["pairs"]["conjugate"]["normal"]["stiffness"] = 2.2656e9  # Table 2, as its number
    doc["simulate"]["sensitivities"] = [pointer]
    found = run_impacts(*parsed(doc))[1]["sensitivities"]["fields"][pointer]
    exact = np.array([values[name] for values in (found["coordinates"], found["velocities"]) for name in values])
    step = 1e-5 * doc["materials"]["hinge"]["E"]
    doc["simulate"]["sensitivities"] = []
    up, down = (end_state(run_impacts(*parsed(variant(doc, pointer, sign * step)))[1]) for sign in (1, -1))
    differences = (up - down) / (2 * step)
    assert np.abs(differences).max() > 0
    np.testing.assert_allclose(exact, differences, atol=1e-5 * np.abs(differences).max())


def test_a_curved_beams_exact_model_enters_by_its_own_stiffness():
    """The exact model is a link (an Euler-Bernoulli arc), condensed like the link above; the
    other models take the closed form. At the drawn state the two stiffnesses are one, so the
    runs agree as the Euler-Bernoulli link's do."""
    closed = run_impacts(*parsed(csfh("6.3", until=0.5)))[1]
    exact_doc = csfh("6.3", until=0.5)
    exact_doc["elements"]["flexure"]["model"] = "exact"
    exact = run_impacts(*parsed(exact_doc))[1]
    np.testing.assert_allclose(impact_times(exact), impact_times(closed), rtol=1e-8)
    np.testing.assert_allclose(
        end_state(exact), end_state(closed), rtol=1e-6, atol=1e-6 * np.abs(end_state(closed)).max()
    )
    exact_doc["simulate"]["sensitivities"] = ["/materials/hinge/E"]  # its numbers are the run's parameters
    assert run_impacts(*parsed(exact_doc))[1]["sensitivities"]["fields"]["/materials/hinge/E"]["unit"] == "GPa"
