"""A circle against a polygon object in impact simulations (models.impacts.pairs): seed 004's
pin (radius 0.18 m, 10 kg) falls from rest under gravity onto a fixed block, on its flat top
or past its corner, and meets it when free fall brings it there."""

from __future__ import annotations

import math

import numpy as np
import pytest

from service.impacts.run import run_impacts
from tests.impact_cases import csfh, parsed

G, RADIUS, TOP, CORNER = 9.81, 0.18, -0.3, 1.0  # the block's top at y = -0.3 m, its right edge at x = 1 m


def falling_on_a_block(scheme: str, start_x: float) -> dict:
    doc = csfh("6.1", scheme=scheme, until=0.25, step=1e-5 if scheme == "moreau" else 1e-4)
    doc["contacts"]["objects"] = {"block": {"type": "polygon", "vertices": [[-1, -1], [0, -1], [0, 0], [-1, 0]],
                                            "position": [CORNER, TOP]}}
    doc["contacts"]["pairs"]["conjugate"]["object"] = "block"
    doc["simulate"]["initial"]["hinge"] = {"displacement": [start_x, 0, 0]}
    return doc


@pytest.mark.parametrize("scheme", ["event_driven", "moreau"])
def test_a_pin_falling_on_the_flat_top_meets_it_after_free_fall(scheme):
    report = run_impacts(*parsed(falling_on_a_block(scheme, 0.0)))[1]
    drop = -TOP - RADIUS
    first = report["impacts"][0]
    if scheme == "event_driven":
        assert first["time"] == pytest.approx(math.sqrt(2 * drop / G), rel=1e-8)
        assert first["impact_speed"] == pytest.approx(math.sqrt(2 * G * drop), rel=1e-8)
    else:
        assert abs(first["time"] - math.sqrt(2 * drop / G)) <= 1e-5
    x = np.array(report["coordinates"]["hinge.x"])
    assert np.abs(x).max() < 1e-6  # pushed straight up by the top edge


def test_a_pin_falling_past_the_corner_meets_the_vertex_and_is_pushed_away_from_it():
    """Its centre 0.1 m beyond the corner: it meets the vertex when (y - top)^2 + 0.1^2 = R^2,
    and the vertex pushes it along the line from the vertex to its centre (down and right)."""
    offset = 0.1
    report = run_impacts(*parsed(falling_on_a_block("event_driven", CORNER + offset)))[1]
    drop = -TOP - math.sqrt(RADIUS**2 - offset**2)
    first = report["impacts"][0]
    assert first["time"] == pytest.approx(math.sqrt(2 * drop / G), rel=1e-8)
    times, vx = np.array(report["times"]), np.array(report["velocities"]["hinge.x"])
    after = times > first["time"] + first["duration"]
    assert vx[after][0] > 0.1 * first["impact_speed"]  # the vertex threw it sideways
    assert np.abs(vx[times < first["time"]]).max() < 1e-9
