"""Rigid bodies with clearance impacts (seed 004): located events, the laws' exact
restitution, Moreau's impact law, energy, and the flexure against an independent
implementation of the paper's Eqs. 5-9."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from impact_cases import as_moreau, csfh, parsed, with_pair
from scipy.integrate import solve_ivp
from scipy.special import ellipk

from flexmech.models.contact.laws import NORMAL_LAWS
from flexmech.models.contact.laws.penalty import effective_restitution
from flexmech.models.impacts.model import impact_model
from flexmech.service.impacts.run import run_impacts

G = 9.81
FALL = 0.03  # from y = 0.01 to the surface at y = -0.02


def run(doc: dict):
    document, spec = parsed(doc)
    return run_impacts(document, spec)[1]


def test_the_central_impact_is_located_at_the_free_fall_time_and_speed():
    report = run(csfh("6.1", until=0.1))
    first = report["impacts"][0]
    assert first["time"] == pytest.approx(math.sqrt(2 * FALL / G), rel=1e-9)  # 0.0782062 s
    assert first["impact_speed"] == pytest.approx(math.sqrt(2 * G * FALL), rel=1e-9)  # 0.767203 m/s
    assert report["events"][0]["kind"] == "contact"


def test_moreau_rebounds_with_exactly_its_restitution_at_every_impact():
    report = run(csfh("6.1", scheme="moreau", step=1e-5, until=1.0))
    impacts = report["impacts"]
    assert len(impacts) >= 5
    for hit in impacts:
        assert hit["rebound_ratio"] == pytest.approx(0.9, abs=1e-9)
    assert impacts[0]["time"] == pytest.approx(math.sqrt(2 * FALL / G), abs=1e-5)  # within a step


def _one_dof_rebound(d: float) -> float:
    """An independent quadrature: x'' = -x^1.5 (1 + d x' / 1) from x = 0, x' = 1, to x = 0."""

    def rhs(t, y):
        return [y[1], -(max(y[0], 0.0) ** 1.5) * (1 + d * y[1])]

    def out(t, y):
        return y[0]

    out.terminal, out.direction = True, -1
    sol = solve_ivp(rhs, (0, 50), [0.0, 1.0], events=out, rtol=1e-12, atol=1e-14, method="DOP853", first_step=1e-6)
    return -sol.y_events[0][-1][1]


@pytest.mark.parametrize("law", ["lankarani_nikravesh", "hunt_crossley", "flores"])
def test_each_law_rebounds_with_its_exact_effective_restitution(law):
    """A body thrown at the hole's wall without gravity: its rebound ratio is the law's
    closed-form effective restitution (0.9132 for Lankarani-Nikravesh with c_r = 0.9), which
    an independent quadrature of the one-degree-of-freedom impact confirms."""
    d = NORMAL_LAWS[law].damping_factor(0.9)
    exact = effective_restitution(d)
    assert exact == pytest.approx(_one_dof_rebound(d), abs=1e-8)
    doc = with_pair(csfh("6.1", until=0.1), law=law)
    doc["gravity"] = [0, 0]
    doc["simulate"]["initial"]["hinge"] = {"displacement": [0, 0, 0], "velocity": [0, -0.5, 0]}
    report = run(doc)
    assert report["impacts"][0]["rebound_ratio"] == pytest.approx(exact, abs=1e-6)
    if law == "lankarani_nikravesh":
        assert exact == pytest.approx(0.91318, abs=1e-5)


def test_energy_is_conserved_between_impacts_and_the_balance_closes():
    report = run(csfh("6.3", until=0.5))
    energies = {k: np.array(v) for k, v in report["energies"].items()}
    total = energies["kinetic"] + energies["elastic"] + energies["gravity"]
    free = np.array(report["contacts"]["conjugate"]["in_contact"]) < 0.5
    scale = np.abs(total).max()
    drift, segments, start = 0.0, 0, None
    for k in range(len(total)):
        if free[k] and start is None:
            start = k
        if (not free[k] or k == len(total) - 1) and start is not None:
            stop = k if free[k] else k - 1
            segment = total[start : stop + 1]
            drift = max(drift, float(np.ptp(segment)) / scale)
            assert np.all(np.diff(segment) <= 1e-9 * scale)  # never increases
            segments += 1
            start = None
    assert segments >= 3
    assert drift < 1e-8
    assert report["energy_balance_error"] < 1e-6
    assert energies["contact_work"][-1] < 0 and energies["friction_work"][-1] < 0


def test_moreau_never_gains_energy_in_free_flight():
    report = run(csfh("6.1", scheme="moreau", step=1e-5, until=0.5))
    e = report["energies"]
    total = np.array(e["kinetic"]) + np.array(e["gravity"])
    active = np.array(report["contacts"]["conjugate"]["normal_impulse"]) > 0
    rises = np.diff(total)[~active[1:]]
    assert np.all(rises <= 1e-12 * np.abs(total).max())
    assert report["energy_balance_error"] < 1e-9


def _paper_flexure_force(q: np.ndarray, turning: bool) -> np.ndarray:
    """Seed 004 Eqs. 5-9 with the note's conventions, written independently: Delta = [dr +
    (A - 1) s; theta], K = A3 R3 K_hat R3^T A3^T (A3 = 1 when constant), Q_e = -T_e K Delta;
    K_hat the inverse of seed 000's Eq. 2 with r = 0.144, theta_f = 300 deg."""
    r, t = 0.144, math.radians(300)
    EI = 100e9 * 0.025 * 0.005**3 / 12
    c, s = math.cos(t), math.sin(t)
    C = (
        np.array(
            [
                [r**3 / 4 * (6 * t + math.sin(2 * t) - 8 * s), r**3 / 2 * (c * c - 2 * c + 1), r * r * (t - s)],
                [0, r**3 / 4 * (2 * t - math.sin(2 * t)), r * r * (1 - c)],
                [0, 0, r * t],
            ]
        )
        / EI
    )
    C = np.triu(C) + np.triu(C, 1).T
    K_hat = np.linalg.inv(C)

    def R(a):
        return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])

    R3 = np.eye(3)
    R3[:2, :2] = R(math.radians(30))
    A = R(q[2])
    s_bar = np.array([0.22, 0.1]) + r * np.array([math.cos(t), math.sin(t)])  # Table 1: [0.2920, -0.02471]
    delta = np.concatenate([q[:2] + (A - np.eye(2)) @ s_bar, [q[2]]])
    A3 = np.eye(3)
    if turning:
        A3[:2, :2] = A
    K = A3 @ R3 @ K_hat @ R3.T @ A3.T
    T_e = np.eye(3)
    arm = A @ s_bar
    T_e[2, :2] = [-arm[1], arm[0]]
    return -T_e @ K @ delta


@pytest.mark.parametrize("turning", [False, True])
def test_the_flexure_force_is_the_papers_eqs_5_to_9(turning):
    doc = csfh("6.3")
    doc["gravity"] = [0, 0]
    doc["simulate"]["flexure_stiffness"] = "turning" if turning else "constant"
    model = impact_model(parsed(doc)[0])
    force = ca.Function("f", [model.q, model.v, model.p], [model.force])
    p = model.book.parameter_vector()
    for q in ([0.003, -0.002, 0.0], [0.004, 0.007, 0.05], [-0.01, 0.002, -0.1]):
        ours = np.asarray(force(q, [0, 0, 0], p)).ravel()
        assert ours == pytest.approx(_paper_flexure_force(np.array(q), turning), rel=1e-7, abs=1e-9)


@pytest.mark.parametrize("scheme", ["event_driven", "moreau"])
def test_a_load_that_grows_in_time_drives_the_body_to_the_surface(scheme):
    """No gravity, F_y = -c t on the free body: y = y0 - c t^3 / (6 m) until it meets the
    surface 0.03 m lower, at t = (6 m 0.03 / c)^(1/3) with speed c t^2 / (2 m); the work of the
    load closes the energy balance."""
    c, m = 1000.0, 10.0
    doc = csfh(
        "6.1",
        until=0.2,
        scheme=scheme,
        step=1e-5 if scheme == "moreau" else 1e-4,
        histories={"/loads/push/force/1": f"-{c}*t"},
    )
    doc["gravity"] = [0, 0]
    doc["loads"] = {"push": {"type": "force", "body": "hinge", "force": [0, 0]}}
    report = run(doc)
    t_hit = (6 * m * FALL / c) ** (1 / 3)
    first = report["impacts"][0]
    if scheme == "event_driven":
        assert first["time"] == pytest.approx(t_hit, rel=1e-9)
        assert first["impact_speed"] == pytest.approx(c * t_hit**2 / (2 * m), rel=1e-9)
        assert report["energy_balance_error"] < 1e-6
    else:
        assert first["time"] == pytest.approx(t_hit, abs=2e-5)
        assert first["impact_speed"] == pytest.approx(c * t_hit**2 / (2 * m), rel=1e-4)
        assert report["energy_balance_error"] < 1e-3
    assert report["energies"]["input_work"][-1] > 0


def test_a_history_is_checked_up_to_each_runs_own_end_time():
    """1 / (0.15 - t) is finite over a 0.1 s run and not over a 0.2 s one, also when the
    shorter run's model was built first."""
    from flexmech.models import MechanismError

    doc = csfh("6.1", until=0.1, scheme="moreau", step=1e-4, histories={"/loads/push/force/1": "1/(0.15 - t)"})
    doc["loads"] = {"push": {"type": "force", "body": "hinge", "force": [0, 0]}}
    document, spec = parsed(doc)
    assert run_impacts(document, spec)[1]["status"] == "finished"
    with pytest.raises(MechanismError) as caught:  # the same document, a longer run asked for
        run_impacts(document, spec.model_copy(update={"until": 0.2}))
    assert caught.value.pointer == "/simulate/histories/loads~1push~1force~11"
    assert "not a finite number at t = 0.15 s" in caught.value.problem


def test_only_loads_and_gravity_follow_histories():
    from flexmech.models import MechanismError

    doc = csfh("6.1", until=0.1, histories={"/bodies/hinge/mass": "10 + t"})
    with pytest.raises(MechanismError) as caught:
        run(doc)
    assert caught.value.pointer == "/simulate/histories/bodies~1hinge~1mass"
    assert "cannot change in time in an impact simulation" in caught.value.problem


@pytest.mark.parametrize("scheme", ["event_driven", "moreau"])
def test_a_shaken_frame_meets_the_resting_pin_at_the_kinematic_time_and_speed(scheme):
    """The hole's body follows dy = A sin(w t) (a prescribed displacement), the pin rests at
    its centre without gravity: they meet when A sin(w t) = 0.02, at the hole's speed
    A w cos(w t). Moreau's impact law holds on the relative normal velocity."""
    A, w = 0.03, 10.0
    doc = csfh(
        "6.1",
        until=0.15,
        scheme=scheme,
        step=1e-5 if scheme == "moreau" else 1e-4,
        histories={"/loads/shake/dy": f"{A}*sin({w}*t)"},
        initial={"hinge": {"displacement": [0, 0, 0]}},
    )
    doc["gravity"] = [0, 0]
    doc["loads"] = {"shake": {"type": "displacement", "body": "frame", "dx": 0, "dy": 0, "rotation": 0}}
    report = run(doc)
    t_hit = math.asin(0.02 / A) / w
    first = report["impacts"][0]
    if scheme == "event_driven":
        assert first["time"] == pytest.approx(t_hit, rel=1e-9)
        assert first["impact_speed"] == pytest.approx(A * w * math.cos(w * t_hit), rel=1e-9)
        assert report["energy_balance_error"] < 1e-6
    else:
        assert first["time"] == pytest.approx(t_hit, abs=2e-5)
        assert first["impact_speed"] == pytest.approx(A * w * math.cos(w * t_hit), rel=1e-3)
        assert first["rebound_ratio"] == pytest.approx(0.9, abs=1e-9)
    assert report["coordinates"]["hinge.y"][-1] > 0.005  # knocked upwards


def test_table_2_stiffnesses_follow_from_e_210_gpa_and_the_external_radius():
    """Seed 004 Table 2 (47.35 and 2.27 "GPa") reproduces with E = 210 GPa, R1 R2 / (R1 + R2)
    in Eq. 14 and L = b in Eq. 16 (../shared/notes/seed-004-csfh.md); Table 1's 100 GPa with
    the conformal radius R1 R2 / (R2 - R1) of a pin in a hole gives twice Table 2's spheres."""
    from flexmech.models.contact.laws.penalty import hertz_stiffness

    assert hertz_stiffness("spheres", 210e9, 0.3, 210e9, 0.3, 0.18, 0.20, "external", None) == pytest.approx(
        47.353e9, rel=1e-4
    )
    assert hertz_stiffness("cylinders", 210e9, 0.3, 210e9, 0.3, 0.18, 0.20, "external", 0.025) == pytest.approx(
        2.2656e9, rel=1e-4
    )
    sigma = 2 * (1 - 0.3**2) / 100e9
    conformal = 4 / (3 * sigma) * math.sqrt(0.18 * 0.20 / 0.02)
    assert hertz_stiffness("spheres", 100e9, 0.3, 100e9, 0.3, 0.18, 0.20, "conformal", None) == pytest.approx(conformal)


def test_the_esdu_law_is_solved_exactly():
    """Eq. 18 inverted: F = b exp(1 + W_-1(-q / (a b e))) with scipy's Lambert W, and the
    tangent stiffness against a finite difference."""
    from scipy.special import lambertw

    from flexmech.models.contact.laws.penalty import esdu_force

    sigma, length, clearance = 2 * (1 - 0.09) / 100e9, 0.025, 0.02
    a, b = sigma / length, 4 * length * clearance / sigma
    q = ca.SX.sym("q")
    force, tangent = esdu_force(q, sigma, length, clearance)
    f = ca.Function("f", [q], [force, tangent])
    for depth in (1e-10, 1e-8, 1e-6, 1e-4, 1e-2):
        exact = b * np.exp(1 + lambertw(-depth / (a * b) / np.e, -1).real)
        value, slope = (float(x) for x in f(depth))
        assert value == pytest.approx(exact, rel=1e-12)
        step = depth * 1e-6
        assert slope == pytest.approx((float(f(depth + step)[0]) - float(f(depth - step)[0])) / (2 * step), rel=1e-6)


def _laws(scheme: str, pair: dict) -> dict:
    return as_moreau(pair) if scheme == "moreau" else pair


def _ball(surface: dict, until: float, scheme: str, friction: dict, velocity=(0.0, 0.0, 0.0), drop=0.0) -> dict:
    """A disk (m = 1 kg, R = 0.1 m, I = m R^2 / 2) centred at the origin, `drop` above the
    surface `surface` of the fixed ground."""
    return {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "gravity": [0, -9.81],
        "bodies": {
            "ground": {"fixed": True, "position": [0, 0]},
            "ball": {"position": [0, 0], "mass": 1.0, "inertia": 0.005},
        },
        "contacts": {
            "sites": {"rim": {"type": "circle", "body": "ball", "radius": 0.1}},
            "objects": {"other": surface},
            "pairs": {
                "touch": _laws(
                    scheme,
                    {
                        "site": "rim",
                        "object": "other",
                        "friction": friction,
                        "normal": {"law": "lankarani_nikravesh", "restitution": 0.9, "stiffness": 1e9, "exponent": 1.5},
                    },
                )
            },
        },
        "simulate": {
            "scheme": scheme,
            "until": until,
            "step": 1e-4,
            "tolerance": 1e-10,
            "initial": {"ball": {"displacement": [0, drop, 0], "velocity": list(velocity)}},
        },
    }


@pytest.mark.parametrize(
    "surface",
    [
        {"type": "half_plane", "body": "ground", "point": [0, -0.1], "normal": [0, 1]},
        {"type": "circle", "body": "ground", "centre": [0, -0.35], "radius": 0.25},
        {"type": "half_plane", "point": [0, -0.1], "normal": [0, 1]},
    ],
    ids=["line", "circle", "line_of_no_body"],
)  # an object without a body is fixed in global axes
def test_a_disk_dropped_on_a_line_or_a_circle_lands_at_the_free_fall_time(surface):
    report = run(_ball(surface, 0.2, "event_driven", {"law": "none"}, drop=0.05))
    assert report["impacts"][0]["time"] == pytest.approx(math.sqrt(2 * 0.05 / G), rel=1e-9)
    assert report["impacts"][0]["impact_speed"] == pytest.approx(math.sqrt(2 * G * 0.05), rel=1e-9)


def test_friction_at_the_contact_point_spins_a_sliding_disk_up_to_rolling():
    """The friction force acts at C = O - R n_c (the lever the paper's Eqs. 30 and 38 drop):
    a disk launched sliding at 1 m/s without spin ends rolling at m R^2 / (I + m R^2) = 2/3
    of it, with omega = -v / R (angular momentum about the contact point is conserved)."""
    floor = {"type": "half_plane", "body": "ground", "point": [0, -0.1], "normal": [0, 1]}
    report = run(
        _ball(floor, 0.3, "moreau", {"law": "coulomb", "adherence": 0.3, "sliding": 0.3}, velocity=(1.0, 0.0, 0.0))
    )
    v, w = report["velocities"]["ball.x"][-1], report["velocities"]["ball.theta"][-1]
    assert v == pytest.approx(2 / 3, rel=1e-9)
    assert w == pytest.approx(-v / 0.1, rel=1e-9)
    assert report["energies"]["friction_work"][-1] == pytest.approx(-(0.5 * 1.0 - 0.5 * (1 + 0.5) * v**2), rel=1e-6)


def test_the_csfh_comes_to_rest_on_its_surface_without_chattering():
    """After its bounces the body stays in contact, rocking on the flexure and slipping to and
    fro: the flags switch with a hysteresis, so no event repeats in zero time (a grazing
    body toggled contact 200,000 times at one instant before)."""
    report = run(csfh("6.3", until=3.0))
    assert report["status"] == "finished"
    assert report["steps"] < 20_000
    times = sorted({event["time"] for event in report["events"]})  # one event may flip several flags
    assert min(b - a for a, b in zip(times, times[1:])) > 1e-6
    assert report["contacts"]["conjugate"]["in_contact"][-1] == 1.0
    assert report["energy_balance_error"] < 1e-6


def _pendulum(scheme: str, phi0: float) -> tuple[dict, float, float, float]:
    """A bob (m = 1 kg, I_G = 0.01 kg m^2) pinned 0.5 m above its mass centre, released at phi0
    left of the vertical; a disk of radius 0.05 m at its centre meets a wall when it hangs."""
    m, I_G, l, r = 1.0, 0.01, 0.5, 0.05
    doc = {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "gravity": [0, -9.81],
        "bodies": {
            "ground": {"fixed": True, "position": [0, 0]},
            "bob": {"position": [0, -l], "mass": m, "inertia": I_G},
        },
        "elements": {"hinge": {"type": "pin", "from": "ground", "to": "bob", "at": [0, 0]}},
        "contacts": {
            "sites": {"disk": {"type": "circle", "body": "bob", "radius": r}},
            "objects": {"wall": {"type": "half_plane", "body": "ground", "point": [r, 0], "normal": [-1, 0]}},
            "pairs": {
                "stop": _laws(
                    scheme,
                    {
                        "site": "disk",
                        "object": "wall",
                        "friction": {"law": "none"},
                        "normal": {
                            "law": "lankarani_nikravesh",
                            "restitution": 0.9,
                            "stiffness": 1e10,
                            "exponent": 1.5,
                        },
                    },
                )
            },
        },
        "simulate": {
            "scheme": scheme,
            "until": 0.6,
            "step": 1e-5 if scheme == "moreau" else 1e-4,
            "tolerance": 1e-10,
            "initial": {"bob": {"displacement": [l * math.sin(phi0), l * (1 - math.cos(phi0)), phi0]}},
        },
    }
    I_O = I_G + m * l * l
    quarter = math.sqrt(I_O / (m * G * l)) * ellipk(math.sin(abs(phi0) / 2) ** 2)  # from phi0 to the vertical
    omega = math.sqrt(2 * m * G * l * (1 - math.cos(phi0)) / I_O)
    return doc, quarter, omega, l


@pytest.mark.parametrize("scheme", ["event_driven", "moreau"])
def test_a_pinned_pendulum_strikes_its_stop_after_the_elliptic_quarter_period(scheme):
    """A pin (a constraint held by Lagrange multipliers): released from 0.5 rad the pendulum
    reaches the vertical after sqrt(I_O / (m g l)) K(sin^2(phi0 / 2)) (scipy's ellipk) with
    omega from the energy; just before the stop the pin pulls m (g + l omega^2) upwards."""
    doc, quarter, omega, l = _pendulum(scheme, -0.5)
    report = run(doc)
    first = report["impacts"][0]
    if scheme == "event_driven":
        assert first["time"] == pytest.approx(quarter, rel=1e-8)
        assert first["impact_speed"] == pytest.approx(omega * l, rel=1e-8)
        k = int(np.searchsorted(report["times"], first["time"]))  # the onset: no contact force yet
        assert report["times"][k] == first["time"]
        assert report["joints"]["hinge"]["Fy"][k] == pytest.approx(1.0 * (G + l * omega**2), rel=1e-4)
        assert abs(report["joints"]["hinge"]["Fx"][k]) < 1e-3
        assert report["energy_balance_error"] < 1e-6
    else:
        assert first["time"] == pytest.approx(quarter, abs=2e-5)
        assert first["rebound_ratio"] == pytest.approx(0.9, abs=1e-9)
    x, y = (np.array(report["coordinates"][f"bob.{c}"]) for c in ("x", "y"))
    theta = np.array(report["coordinates"]["bob.theta"])
    pin_x = x - l * np.sin(theta)  # the bob's point at the pin stays at the origin
    pin_y = -l + y + l * np.cos(theta)
    assert np.abs(pin_x).max() < 1e-7 and np.abs(pin_y).max() < 1e-7
