"""An element family of the test's own, added with one registration line, works in statics,
link dynamics and impact simulations (models.elements.base: the contract; models.documents.document
takes its section at once; models.impacts.families brings its statics energy to impacts).

The family is a bushing: a zero-length spring of stiffness k between the point of two bodies
that coincides with `to`'s reference point as drawn, and a torsional spring kt between their
rotations, V = k |p_to - p_from|^2 / 2 + kt (theta_to - theta_from)^2 / 2. Its forces are
linear at any displacement, so each analysis has an exact answer: a static deflection F / k,
a free vibration that Newmark's average acceleration follows on its discrete circle, and an
impact at the time a harmonic motion reaches the hole's clearance."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import casadi as ca
import numpy as np
import pytest
from impact_cases import csfh

from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.models.documents.fields import Number
from flexmech.models.elements import FAMILIES
from flexmech.models.elements.base import Contribution, EnergyTerms, ScaleHint, TwoBodyElement
from flexmech.models.graph.structure import ElementTopology
from flexmech.service.analysis import run_analysis
from flexmech.service.solvers.newton import NewtonOptions

K, KT, MASS, INERTIA = 400.0, 50.0, 10.0, 0.1617  # N/m, N m/rad, kg, kg m^2


class Bushing(TwoBodyElement):
    type: Literal["bushing"]
    stiffness: Number
    rotational_stiffness: Number = 0.0


@dataclass(frozen=True)
class BushingTopology(ElementTopology):
    pass


class BushingFamily:
    type = "bushing"
    schema = Bushing

    def collect(self, c, name: str, el: Bushing, i: int, j: int) -> BushingTopology:
        c.add(f"/elements/{name}/stiffness", el.stiffness, "stiffness", "nonnegative")
        c.add(f"/elements/{name}/rotational_stiffness", el.rotational_stiffness, "rotational_stiffness", "nonnegative")
        c.holds_rotation(i)
        c.holds_rotation(j)
        return BushingTopology(name, self.type, i, j)

    def _energy(self, ctx, t: BushingTopology, d) -> ca.SX:
        i, j = t.start_body, t.end_body
        on_from = ctx.body_axes(i, ctx.reference(j)[0])  # `to`'s reference point, carried by `from`
        gap = ctx.place(j, ca.SX.zeros(2), d) - ctx.place(i, on_from, d)
        base = f"/elements/{t.name}"
        return (
            0.5 * ctx.P[f"{base}/stiffness"] * ca.sumsqr(gap)
            + 0.5 * ctx.P[f"{base}/rotational_stiffness"] * (d[j][2] - d[i][2]) ** 2
        )

    def contribute(self, ctx, t: BushingTopology, d, z) -> Contribution:
        ends = (t.start_body, t.end_body)
        local = [ca.SX.sym(f"d{b}", 3) if b in ends else d[b] for b in range(ctx.n_bodies)]
        energy = self._energy(ctx, t, local)
        stacked, actual = ca.vertcat(*[local[b] for b in ends]), ca.vertcat(*[d[b] for b in ends])
        wrenches = {b: ca.substitute(ca.gradient(energy, local[b]), stacked, actual) for b in ends}
        return Contribution(
            wrenches, outputs=[("energy", "energy", self._energy(ctx, t, d))], energy=self._energy(ctx, t, d)
        )

    def unknowns(self, t) -> list:
        return []

    def energy_terms(self, ctx, t, d) -> EnergyTerms:
        return EnergyTerms(self._energy(ctx, t, d))

    def kinetic_energy(self, ctx, t, d, v) -> None:
        return None

    def scale_hint(self, t, values) -> ScaleHint:
        return ScaleHint(stiffness=values[f"/elements/{t.name}/stiffness"])


@pytest.fixture
def bushing():
    FAMILIES.register(BushingFamily())  # the one registration line
    yield
    FAMILIES.unregister("bushing")


def block_on_a_bushing(**fields) -> dict:
    return {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "bodies": {
            "wall": {"fixed": True, "position": [0, 0]},
            "block": {"position": [0.5, 0.2], "mass": MASS, "inertia": INERTIA},
        },
        "elements": {
            "mount": {"type": "bushing", "from": "wall", "to": "block", "stiffness": K, "rotational_stiffness": KT}
        },
        **fields,
    }


def test_a_document_names_an_unregistered_family_as_an_unknown_type():
    with pytest.raises(MechanismError) as caught:
        load_document(block_on_a_bushing())
    assert caught.value.pointer == "/elements/mount/type"
    assert caught.value.problem == "unknown type 'bushing' (types: curved_beam, link, spring, pin, slider)"


def test_a_registered_family_is_among_the_types_a_document_is_told_of(bushing):
    doc = block_on_a_bushing()
    doc["elements"]["mount"]["type"] = "bushin"
    with pytest.raises(MechanismError) as caught:
        load_document(doc)
    assert caught.value.problem == (
        "unknown type 'bushin' (did you mean 'bushing'? types: curved_beam, link, spring, pin, slider, bushing)"
    )


def test_statics_deflects_the_block_by_load_over_stiffness(bushing):
    doc = block_on_a_bushing(
        loads={
            "push": {"type": "force", "body": "block", "force": [3.0, -4.0]},
            "twist": {"type": "moment", "body": "block", "moment": 2.0},
        }
    )
    report = run_analysis(compile_mechanism(load_document(doc)), "equilibrium", NewtonOptions())
    assert report["status"] == "converged"
    moved = report["displacements"]
    assert moved["block.x"] == pytest.approx(3.0 / K, rel=1e-9)
    assert moved["block.y"] == pytest.approx(-4.0 / K, rel=1e-9)
    assert moved["block.angle"] == pytest.approx(2.0 / KT, rel=1e-9)
    wall = [report["outputs"][f"reactions.wall.{c}"] for c in ("Fx", "Fy")]
    np.testing.assert_allclose(wall, [-3.0, 4.0], rtol=1e-9)  # the wall holds the load


def test_link_dynamics_follows_newmarks_discrete_circle(bushing):
    """Held by 4 N and released, the block swings as x_n = (4 / k) cos(n W), with W = 2
    atan(w h / 2) the average-acceleration rule's phase per step (w = sqrt(k / m)): exact for
    a linear oscillator, so any error in its mass, force or energy shows."""
    step, force = 1e-3, 4.0
    doc = block_on_a_bushing(
        loads={"hold": {"type": "force", "body": "block", "force": [force, 0.0]}},
        simulate={
            "until": 0.5,
            "step": step,
            "scheme": "newmark",
            "a1": 0.5,
            "a2": 0.5,
            "start": "equilibrium",
            "histories": {"/loads/hold/force/0": 0},
        },
    )
    report = run_analysis(compile_mechanism(load_document(doc)), "simulate", NewtonOptions())
    assert report["status"] == "finished", report["message"]
    times, x = np.array(report["times"]), np.array(report["outputs"]["bodies.block.x"]) - 0.5
    phase = 2 * math.atan(math.sqrt(K / MASS) * step / 2)
    np.testing.assert_allclose(x, force / K * np.cos(np.round(times / step) * phase), atol=1e-9 * force / K)
    strain = np.array(report["outputs"]["elements.mount.energy"])  # the family's own output
    np.testing.assert_allclose(strain, 0.5 * K * x**2, rtol=1e-9, atol=1e-15)
    assert report["energy_balance_error"] <= 1e-12  # the rule keeps a linear oscillator's energy


@pytest.mark.parametrize("scheme", ["event_driven", "moreau"])
def test_an_impact_run_meets_the_hole_when_the_harmonic_motion_reaches_the_clearance(bushing, scheme):
    """The seed 004 pin (10 kg) in its hole (clearance 20 mm), held by a bushing, no gravity,
    set moving at v0 along x: x = v0 sin(w t) / w meets the hole at asin(w c / v0) / w with
    speed sqrt(v0^2 - w^2 c^2)."""
    v0, clearance = 0.3, 0.02
    doc = csfh("6.1", scheme=scheme, until=0.1, step=1e-5 if scheme == "moreau" else 1e-4)
    doc["gravity"], doc["units"]["angle"] = None, "rad"
    doc["elements"] = {
        "mount": {"type": "bushing", "from": "frame", "to": "hinge", "stiffness": K, "rotational_stiffness": KT}
    }
    doc["simulate"]["initial"]["hinge"] = {"displacement": [0, 0, 0], "velocity": [v0, 0, 0]}
    report = run_analysis(compile_mechanism(load_document(doc)), "simulate", NewtonOptions())
    w = math.sqrt(K / MASS)
    first = report["impacts"][0]
    meets = math.asin(w * clearance / v0) / w
    if scheme == "event_driven":
        assert first["time"] == pytest.approx(meets, rel=1e-8)
        assert first["impact_speed"] == pytest.approx(math.sqrt(v0**2 - (w * clearance) ** 2), rel=1e-8)
    else:
        assert abs(first["time"] - meets) <= 1e-5  # within a step
    times, x = np.array(report["times"]), np.array(report["coordinates"]["hinge.x"])
    before = times < first["time"] - 1e-3
    np.testing.assert_allclose(x[before], v0 * np.sin(w * times[before]) / w, atol=1e-7)


def test_the_graph_caches_are_keyed_by_a_registered_familys_source():
    """Graphs on disk are named by the code they come from: a family registered from outside
    the models package brings its file into that key, so editing it never loads stale graphs."""
    from flexmech.models.caches.graph_cache import code_version

    before = code_version()
    FAMILIES.register(BushingFamily())
    try:
        assert __file__ in FAMILIES.sources()
        assert code_version() != before
    finally:
        FAMILIES.unregister("bushing")
    assert code_version() == before
