"""The modes analysis (service.vibration) against closed forms: a cantilever's beta L and its
effective modal masses, the Table 4.1 rod's period, a pinned-pinned link under axial tension and
compression (prestress, down to buckling), rigid bodies on springs and on a curved-beam flexure,
and bad input named by its field."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import EXAMPLES
from scipy.linalg import eigh
from scipy.optimize import brentq

from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service.analyses import ANALYSES
from flexmech.service.analyses.base import AnalysisRequest
from flexmech.service.vibration.eigen import vibration_eigen

E, G_SHEAR, RHO = 2e11, 8e10, 7850.0
B, H, L = 0.0127, 0.0003, 1.11  # a slender strip: its rotary inertia moves beta L by < 1e-7
AREA, SECOND = B * H, B * H**3 / 12
BETA_L = (1.875104068711961, 4.694091132974175, 7.854757438237613)  # roots of cos(x) cosh(x) = -1
EFFECTIVE = (0.6131, 0.1883, 0.0647)  # a cantilever's effective modal masses, of its whole


def strip(intervals: int, **link) -> dict:
    return {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "materials": {"steel": {"E": E, "G": G_SHEAR, "density": RHO}},
        "sections": {"strip": {"b": B, "h": H}},
        "bodies": {"clamp": {"fixed": True, "position": [0, 0]}, "tip": {"position": [L, 0]}},
        "elements": {
            "strip": {
                "type": "link",
                "from": "clamp",
                "to": "tip",
                "length": L,
                "material": "steel",
                "section": "strip",
                "discretization": "elements",
                "intervals": intervals,
                "degree": 3,
                **link,
            }
        },
    }


def modes(document: dict | str, **options) -> dict:
    mech = compile_mechanism(load_document(document))
    return ANALYSES.named("modes").run(mech, AnalysisRequest(given=options))


def beta_l(report: dict) -> np.ndarray:
    omega = np.array([m["omega"] for m in report["modes"]])
    return (omega**2 * RHO * AREA / (E * SECOND)) ** 0.25 * L


def test_a_cantilever_has_the_beta_l_of_euler_bernoulli_at_order_2p_in_its_elements():
    """Degree-3 elements: the third beta L's error falls by 2^6 per halving (2p = 6), and at 8
    elements all three are within 1e-5 (measured: 7e-9, 1e-7, 2.6e-6)."""
    errors = []
    for intervals in (2, 4, 8):
        report = modes(strip(intervals), count=3, at="undeformed")
        assert report["coordinates"] == "elements" and [m["kind"] for m in report["modes"]] == ["elastic"] * 3
        errors.append(np.abs(beta_l(report) / BETA_L - 1))
    assert errors[-1].max() < 1e-5
    order = math.log2(errors[1][2] / errors[2][2])
    assert 5.5 < order < 6.5, order
    fractions = [m["effective_mass_fraction"]["y"] for m in report["modes"]]
    assert fractions == pytest.approx(EFFECTIVE, abs=5e-4)
    assert all(m["effective_mass"]["x"] < 1e-20 for m in report["modes"])  # bending moves nothing along the strip
    assert report["total_mass"] == pytest.approx(RHO * AREA * L, rel=1e-12)
    assert all(m["energy_shares"] == {"elements/strip": pytest.approx(1.0)} for m in report["modes"])


def test_the_table_4_1_rod_has_its_first_period():
    report = modes(str(EXAMPLES / "rod_free_vibration.json"), count=2, at="undeformed")
    assert report["modes"][0]["period"] == pytest.approx(0.47221, rel=2e-5)
    assert report["modes"][0]["frequency"] == pytest.approx(1 / report["modes"][0]["period"])


def pinned_pinned(axial_force: float) -> dict:
    """The strip pinned at both ends, its far end on a rail along it, pulled by `axial_force`
    (negative: pushed)."""
    doc = strip(8, start="pinned", end="pinned")
    doc["bodies"]["tip"]["joint"] = True
    doc["elements"]["rail"] = {"type": "slider", "from": "clamp", "to": "tip", "angle": 0}
    doc["loads"] = {"pull": {"type": "force", "body": "tip", "force": [axial_force, 0.0]}}
    return doc


EULER = math.pi**2 * E * SECOND / L**2


@pytest.mark.parametrize("pull", [0.05, 1.0, -0.5], ids=["small tension", "Euler load", "half Euler compression"])
def test_axial_force_stiffens_a_pinned_pinned_link_as_the_string_beam_formula_says(pull):
    """omega_1^2 = (pi/L)^4 EI/(rho A) + (pi/L)^2 P/(rho A): doubled at P = P_cr, halved at -P_cr/2."""
    report = modes(pinned_pinned(pull * EULER), count=1)
    assert report["status"] == "converged"
    expected = (math.pi / L) ** 4 * E * SECOND / (RHO * AREA) + (math.pi / L) ** 2 * pull * EULER / (RHO * AREA)
    assert report["modes"][0]["omega_squared"] == pytest.approx(expected, rel=1e-5)
    bare = (math.pi / L) ** 4 * E * SECOND / (RHO * AREA)
    assert report["modes"][0]["omega_squared"] / bare == pytest.approx(1 + pull, rel=1e-5)


def test_past_the_euler_load_the_straight_link_is_unstable_and_its_frequency_goes_to_zero_at_it():
    near = modes(pinned_pinned(-0.999 * EULER), count=1)["modes"][0]
    assert near["kind"] == "elastic" and near["omega_squared"] / ((math.pi / L) ** 4 * E * SECOND / (RHO * AREA)) == (
        pytest.approx(0.001, rel=1e-2)
    )
    beyond = modes(pinned_pinned(-1.05 * EULER), count=1)
    assert beyond["modes"][0]["kind"] == "unstable" and beyond["modes"][0]["omega_squared"] < 0
    assert "unstable" in beyond["warnings"][-1]


def body_on_springs(mass: float, inertia: float, k: float, k_turn: float) -> dict:
    return {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "bodies": {
            "ground": {"fixed": True, "position": [0, 0]},
            "carriage": {"position": [1, 0], "mass": mass},
            "wheel": {"position": [0, 2], "mass": mass, "inertia": inertia},
        },
        "elements": {
            "rail": {"type": "slider", "from": "ground", "to": "carriage", "angle": 0},
            "coil": {"type": "spring", "from": "ground", "to": "carriage", "from_at": [0, 0], "stiffness": k},
            "axle": {"type": "pin", "from": "ground", "to": "wheel", "at": [0, 2]},
            "torsion": {"type": "spring", "kind": "torsional", "from": "ground", "to": "wheel", "stiffness": k_turn},
        },
    }


def test_a_body_on_a_spring_vibrates_at_the_square_root_of_k_over_m():
    m, J, k, kt = 0.3, 0.002, 1200.0, 4.5
    report = modes(body_on_springs(m, J, k, kt), count=2, at="undeformed")
    omegas = sorted([math.sqrt(k / m), math.sqrt(kt / J)])
    assert [mode["omega"] for mode in report["modes"]] == pytest.approx(omegas, rel=1e-10)
    carriage = next(mode for mode in report["modes"] if "bodies/carriage" in mode["energy_shares"])
    assert carriage["energy_shares"]["bodies/carriage"] == pytest.approx(1.0)
    assert carriage["effective_mass"]["x"] == pytest.approx(m, rel=1e-10)  # the whole carriage moves with it


def platform_on_a_flexure() -> dict:
    return {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg", "stress": "Pa"},
        "materials": {"steel": {"E": 2e11}},
        "sections": {"blade": {"b": 0.005, "h": 0.0005}},
        "bodies": {
            "frame": {"fixed": True, "position": [0, 0]},
            "platform": {"position": [0.04, 0.0], "mass": 0.05, "inertia": 4e-5, "center_of_mass": [0.005, 0.002]},
        },
        "elements": {
            "hinge": {
                "type": "curved_beam",
                "from": "frame",
                "to": "platform",
                "center": [0.02, 0.0],
                "radius": 0.02,
                "start_angle": math.pi,
                "arc_angle": math.pi,
                "material": "steel",
                "section": "blade",
            }
        },
    }


def test_a_platform_on_a_curved_beam_vibrates_with_the_flexures_tangent_stiffness_and_its_mass():
    """The constant-stiffness flexure is massless: the modes are those of K_T (the linearization
    analysis' numbers) with the platform's rigid-body mass matrix, written out here."""
    doc = platform_on_a_flexure()
    report = modes(doc, count=3, at="undeformed")
    assert report["coordinates"] == "bodies"
    mech = compile_mechanism(load_document(doc))
    K = np.array(
        ANALYSES.named("linearization").run(mech, AnalysisRequest(given={"at": "undeformed"}))["stiffness"]["K"]
    )
    m, J, (cx, cy) = 0.05, 4e-5, (0.005, 0.002)
    M = np.array([[m, 0, -m * cy], [0, m, m * cx], [-m * cy, m * cx, J]])  # J about the reference point
    expected = np.sqrt(eigh(0.5 * (K + K.T), M, eigvals_only=True))
    assert [mode["omega"] for mode in report["modes"]] == pytest.approx(expected, rel=1e-9)
    assert sum(mode["effective_mass"]["x"] + mode["effective_mass"]["y"] for mode in report["modes"]) == (
        pytest.approx(2 * m, rel=1e-9)  # every mode counted: the platform's whole mass, along each direction
    )


def test_a_mechanism_without_mass_is_refused_naming_where_mass_goes():
    doc = body_on_springs(0.3, 0.002, 1200.0, 4.5)
    for body in ("carriage", "wheel"):
        del doc["bodies"][body]["mass"]
    del doc["bodies"]["wheel"]["inertia"]
    with pytest.raises(MechanismError) as err:
        modes(doc, at="undeformed")
    assert err.value.pointer == "/bodies" and "no mass" in str(err.value)


def test_more_modes_than_the_mechanism_has_are_refused_with_how_many_it_has():
    with pytest.raises(MechanismError) as err:
        modes(body_on_springs(0.3, 0.002, 1200.0, 4.5), count=3, at="undeformed")
    assert err.value.pointer == "/count" and "3 modes asked, but the mechanism has 2" in str(err.value)


def test_a_massless_motion_nothing_holds_is_named():
    doc = body_on_springs(0.3, 0.002, 1200.0, 4.5)
    del doc["elements"]["torsion"]
    del doc["bodies"]["wheel"]["inertia"]
    doc["bodies"]["wheel"]["mass"] = 0.0
    with pytest.raises(MechanismError) as err:
        modes(doc, at="undeformed")
    assert "neither mass nor stiffness" in str(err.value)


def test_shift_invert_finds_the_lowest_modes_of_a_long_chain_as_the_closed_form():
    """A fixed-free chain of 600 equal masses and springs (past the dense limit): omega_j =
    2 sqrt(k/m) sin((2j - 1) pi / (2 (2N + 1)))."""
    n, k, m = 600, 3.0e4, 0.02
    K = np.diag(np.full(n, 2 * k)) - np.diag(np.full(n - 1, k), 1) - np.diag(np.full(n - 1, k), -1)
    K[-1, -1] = k
    found = vibration_eigen(K, np.eye(n) * m, None, 5)
    j = np.arange(1, 6)
    exact = 2 * math.sqrt(k / m) * np.sin((2 * j - 1) * math.pi / (2 * (2 * n + 1)))
    assert np.sqrt(found.omega_squared) == pytest.approx(exact, rel=1e-9)
    assert np.einsum("im,ij,jm->m", found.shapes, np.eye(n) * m, found.shapes) == pytest.approx(np.ones(5))


def test_an_elastic_contact_law_stiffens_the_mode_by_its_tangent():
    """A 2 kg block on a 400 N/m spring and a rail, pushed by 10 N into a stop through Hertz's
    law F = K q^1.5 (K = 2e6 N/m^1.5): about the equilibrium the block vibrates at
    omega^2 = (k + 1.5 K q^0.5) / m, q its indentation there (the penalty law is a stiffness)."""
    k, K, m, push, gap, pad = 400.0, 2e6, 2.0, 10.0, 0.01, 0.02
    doc = {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "bodies": {"wall": {"fixed": True, "position": [0, 0]}, "block": {"position": [0.5, 0], "mass": m}},
        "elements": {
            "spring": {"type": "spring", "from": "wall", "to": "block", "stiffness": k},
            "rail": {"type": "slider", "from": "wall", "to": "block", "angle": 0},
        },
        "loads": {"push": {"type": "force", "body": "block", "force": [push, 0]}},
        "contacts": {
            "sites": {"pad": {"type": "circle", "body": "block", "centre": [0, 0], "radius": pad}},
            "objects": {"stop": {"type": "half_plane", "point": [0.5 + pad + gap, 0], "normal": [-1, 0]}},
            "pairs": {
                "touch": {"site": "pad", "object": "stop", "normal": {"law": "hertz", "stiffness": K, "exponent": 1.5}}
            },
        },
    }
    x = brentq(lambda x: k * x + K * max(x - gap, 0) ** 1.5 - push, 0, 0.1, xtol=1e-16)
    report = modes(doc, count=1)
    assert report["modes"][0]["omega_squared"] == pytest.approx((k + 1.5 * K * (x - gap) ** 0.5) / m, rel=1e-9)
    free = modes({**doc, "loads": {}}, count=1)  # not touching: the spring alone
    assert free["modes"][0]["omega_squared"] == pytest.approx(k / m, rel=1e-12)


def pressed_against_a_wall(push: float) -> dict:
    """A body (mass m, inertia J about its reference point, its mass centre) on springs along x
    and y (1 m long; the y one leans 10 mm so that it stands upright once pressed) and a torsion
    spring, a round pad of radius R at (0, d) from its reference point, a frictionless rigid wall
    10 mm beyond the pad, pushed along x: the push, the x spring and the wall's force all act at
    the pad's height, so nothing turns the body."""
    m, J, kx, ky, kt, R, d = 0.4, 2e-3, 900.0, 300.0, 2.0, 0.02, 0.05
    return {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "bodies": {
            "ground": {"fixed": True, "position": [0, 0]},
            "block": {"position": [0.5, 0], "mass": m, "inertia": J},
        },
        "elements": {
            "kx": {
                "type": "spring",
                "from": "ground",
                "to": "block",
                "from_at": [-0.5, d],
                "to_at": [0.5, d],
                "stiffness": kx,
            },
            "ky": {"type": "spring", "from": "ground", "to": "block", "from_at": [0.51, -1], "stiffness": ky},
            "kt": {"type": "spring", "kind": "torsional", "from": "ground", "to": "block", "stiffness": kt},
        },
        "loads": {"push": {"type": "force", "body": "block", "offset": [0, d], "force": [push, 0]}},
        "contacts": {
            "sites": {"pad": {"type": "circle", "body": "block", "centre": [0, d], "radius": R}},
            "objects": {"wall": {"type": "half_plane", "point": [0.5 + R + 0.01, 0], "normal": [-1, 0]}},
            "pairs": {"touch": {"site": "pad", "object": "wall"}},
        },
    }


def test_a_closed_contact_holds_its_normal_motion_in_the_modes():
    """Pressed (30 N against kx's 9 N at the wall): the pad stays on the wall, so the reference
    point moves along x by d sin(theta) as the body turns (the x spring's end, on the pad's line,
    stays): omega_y^2 = (ky + T_x / l_x) / m and omega_turn^2 = (kt + T_y d^2 / l_y - T_x d y0 / l_x)
    / (J + m d^2), T the springs' tensions there (kx stretched 10 mm; ky upright and a little short,
    pushed across by the turn) and y0 the body's rise, which tilts the x spring by y0 / l_x so that
    the turn (its end rising by -d theta^2 / 2) shortens it. Open (5 N): the modes without the wall."""
    m, J, kx, ky, kt, d = 0.4, 2e-3, 900.0, 300.0, 2.0, 0.05
    closed = modes(pressed_against_a_wall(30.0), at="contact", count=2)
    assert closed["status"] == "converged" and closed["contacts"] == {"touch": "frictionless"}
    rest_y, tension_x = math.sqrt(1 + 0.01**2), kx * 0.01
    rise = ky * (rest_y - 1) / (ky + tension_x / 1.01)
    tension_y = ky * (1 + rise - rest_y)
    turn = kt + tension_y * d**2 / (1 + rise) - tension_x * d * rise / 1.01
    expected = sorted([(ky + tension_x / 1.01) / m, turn / (J + m * d**2)])
    assert [mode["omega_squared"] for mode in closed["modes"]] == pytest.approx(expected, rel=1e-8)
    assert closed["available"] == 2  # the normal motion is held
    free = modes(pressed_against_a_wall(5.0), at="contact", count=3)
    assert free["contacts"] == {"touch": "open"}
    apart = pressed_against_a_wall(5.0)
    del apart["contacts"]  # nothing touches: the modes of the equilibrium without the wall
    expected = [mode["omega_squared"] for mode in modes(apart, count=3)["modes"]]
    assert [mode["omega_squared"] for mode in free["modes"]] == pytest.approx(expected, rel=1e-8)


def test_the_arch_snap_through_paths_stability_and_the_modes_agree_at_every_point():
    """The clamped arch (examples/snap_through_arch.json) with a 10 g mass at its crown, traced
    through both limit points: at each of the path's states (both branches) the continuation calls
    the state stable exactly when every mode is elastic, and omega_1^2 falls toward zero at the
    first limit point."""
    from flexmech.service.solvers.continuation import trace_path
    from flexmech.service.vibration.modes import mechanism_modes

    doc = json.loads((EXAMPLES / "snap_through_arch.json").read_text())
    doc["bodies"]["crown"].update(mass=0.01, inertia=1.0)
    doc["units"]["mass"] = "kg"
    mech = compile_mechanism(load_document(doc))
    path = trace_path(mech, "/loads/P/force/1", -300.0, 20.0)
    assert [lp.kind for lp in path.limit_points] == ["minimum", "maximum"]
    verdicts, lowest = [], []
    for point in path.points:
        eigen = mechanism_modes(mech.with_values({"/loads/P/force/1": point.value}), point.z, None).eigen
        verdicts.append((point.stability.stable, all(kind == "elastic" for kind in eigen.kinds)))
        lowest.append(eigen.omega_squared[0])
    assert all(static == dynamic for static, dynamic in verdicts) and not all(s for s, _ in verdicts)
    before = path.limit_points[0].after_point
    assert lowest[before] < 0.1 * lowest[0] and lowest[before] > 0 > lowest[before + 1]


def test_the_sparse_bordered_solver_agrees_with_the_dense_one_with_constraints_and_massless_nodes():
    """A fixed-free chain of 900 nodes, the odd ones massless, two pairs tied by constraints: the
    sparse shift-invert on the bordered pencil (taken past 400 unknowns for a few modes) finds
    the dense solver's lowest six modes (every mode asked: the null space and the massless
    condensation formed)."""
    n, k, m = 900, 3e4, 0.02
    K = np.diag(np.full(n, 2 * k)) - np.diag(np.full(n - 1, k), 1) - np.diag(np.full(n - 1, k), -1)
    K[-1, -1] = k
    M = np.diag(np.where(np.arange(n) % 2 == 0, m, 0.0))
    G = np.zeros((2, n))
    G[0, 10], G[0, 11], G[1, 200], G[1, 201] = 1, -1, 1, -1
    sparse, dense = vibration_eigen(K, M, G, 6), vibration_eigen(K, M, G, None)
    assert sparse.omega_squared == pytest.approx(dense.omega_squared[:6], rel=1e-10)
    assert sparse.kinds == ["elastic"] * 6
    assert np.einsum("im,ij,jm->m", sparse.shapes, M, sparse.shapes) == pytest.approx(np.ones(6))
    assert np.abs(G @ sparse.shapes).max() < 1e-9 * np.abs(sparse.shapes).max()  # the ties hold
    overlap = np.abs(np.einsum("im,ij,jm->m", sparse.shapes, M, dense.shapes[:, :6]))
    assert overlap == pytest.approx(np.ones(6), rel=1e-8)  # the same shapes, up to sign


def test_a_structure_too_large_for_the_modal_graphs_is_refused_before_they_are_built():
    doc = json.loads((EXAMPLES / "rod_free_vibration.json").read_text())
    doc["elements"]["rod"]["intervals"] = 16  # 16 x 3 x 3 = 144 own unknowns: its graphs take 14 s
    with pytest.raises(MechanismError) as err:
        modes(doc, at="undeformed")
    assert err.value.pointer == "/document/elements/rod/intervals" and "at most 96 unknowns" in str(err.value)
