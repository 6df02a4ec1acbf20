"""The frequency_response analysis against closed forms: a damped mass on a spring (the whole
curve, the peak, the half-power bandwidth), Rayleigh's mass term, a cantilever's static
compliance, the static gain against finite differences of equilibria (a prestressed rod, a
platform on a curved-beam flexure), and bad input named by its field."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import EXAMPLES
from test_modes import body_on_springs, platform_on_a_flexure, strip

from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service.analyses import ANALYSES
from flexmech.service.analyses.base import AnalysisRequest
from flexmech.service.solvers.equilibrium import solve_equilibrium
from flexmech.service.units import outputs_in_doc_units

M, J, K, K_TURN = 0.3, 0.002, 1200.0, 4.5


def respond(document, **options) -> dict:
    mech = compile_mechanism(load_document(document))
    return ANALYSES.named("frequency_response").run(mech, AnalysisRequest(given=options))


def shaken() -> dict:
    doc = body_on_springs(M, J, K, K_TURN)
    doc["loads"] = {"shake": {"type": "force", "body": "carriage", "force": [0.0, 0.0]}}
    return doc


def test_a_damped_mass_on_a_spring_responds_as_the_closed_form():
    zeta = 0.02
    report = respond(shaken(), input="/loads/shake/force/0", outputs=["bodies.carriage.x"], damping_ratio=zeta)
    f = np.array(report["frequencies"])
    omega, omega_n = 2 * math.pi * f, math.sqrt(K / M)
    exact = 1 / (K - M * omega**2 + 2j * zeta * math.sqrt(K * M) * omega)
    response = report["responses"]["bodies.carriage.x"]
    assert response["unit"] == "m/N" and response["static"] == pytest.approx(1 / K, rel=1e-12)
    assert response["amplitude"] == pytest.approx(np.abs(exact), rel=1e-9)
    assert response["phase"] == pytest.approx(np.degrees(np.angle(exact)), abs=1e-7)
    (peak,) = report["resonances"]  # the wheel's mode does not move the carriage
    assert peak["mode"] == 2 and peak["output"] == "bodies.carriage.x"
    assert peak["frequency"] == pytest.approx(omega_n * math.sqrt(1 - 2 * zeta**2) / (2 * math.pi), rel=1e-8)
    assert peak["amplitude"] == pytest.approx(1 / (2 * zeta * math.sqrt(1 - zeta**2) * K), rel=1e-9)
    half_power = [1 - 2 * zeta**2 + s * 2 * zeta * math.sqrt(1 - zeta**2) for s in (-1, 1)]  # (omega / omega_n)^2
    bandwidth = omega_n * (math.sqrt(half_power[1]) - math.sqrt(half_power[0])) / (2 * math.pi)
    assert peak["bandwidth"] == pytest.approx(bandwidth, rel=1e-6)
    assert peak["quality"] == pytest.approx(peak["frequency"] / bandwidth, rel=1e-6)
    assert np.sum(np.abs(f - omega_n / (2 * math.pi)) < 3 * zeta * omega_n / (2 * math.pi)) >= 40  # refined there


def test_a_response_over_many_blocks_of_frequencies_is_the_closed_form_at_each():
    """20000 points are evaluated a block of FREQUENCY_BLOCK at a time: every one as exact."""
    from flexmech.service.vibration.frf import FREQUENCY_BLOCK

    zeta = 0.02
    report = respond(
        shaken(), input="/loads/shake/force/0", outputs=["bodies.carriage.x"], damping_ratio=zeta, points=20_000
    )
    f = np.array(report["frequencies"])
    assert len(f) > 4 * FREQUENCY_BLOCK
    omega = 2 * math.pi * f
    exact = 1 / (K - M * omega**2 + 2j * zeta * math.sqrt(K * M) * omega)
    assert report["responses"]["bodies.carriage.x"]["amplitude"] == pytest.approx(np.abs(exact), rel=1e-9)


def test_rayleighs_mass_term_damps_as_a_dashpot_of_alpha_m():
    alpha = 3.0
    report = respond(
        shaken(),
        input="/loads/shake/force/0",
        outputs=["bodies.carriage.x"],
        damping_ratio=0,
        mass_damping=alpha,
        start=1,
        stop=100,
        points=50,
    )
    omega = 2 * math.pi * np.array(report["frequencies"])
    exact = np.abs(1 / (K - M * omega**2 + 1j * alpha * M * omega))
    assert report["responses"]["bodies.carriage.x"]["amplitude"] == pytest.approx(exact, rel=1e-9)
    assert report["frequencies"][0] == 1 and report["frequencies"][-1] == 100


def test_a_cantilevers_tip_follows_its_static_compliance_at_low_frequency():
    """3EI/L^3 at the tip (cubic rotations: the displacement elements are exact for a tip load)."""
    doc = strip(4)
    doc["loads"] = {"push": {"type": "force", "body": "tip", "force": [0.0, 0.0]}}
    report = respond(doc, input="/loads/push/force/1", outputs=["bodies.tip.y"], at="undeformed", start=1e-3, stop=1)
    E, b, h, L = 2e11, 0.0127, 0.0003, 1.11
    compliance = L**3 / (3 * E * b * h**3 / 12)
    response = report["responses"]["bodies.tip.y"]
    assert response["static"] == pytest.approx(compliance, rel=1e-9)
    first = report["natural_frequencies"][0]  # 0.199 Hz: at 1 mHz the response is static but for (f / f_1)^2
    assert response["amplitude"][0] == pytest.approx(compliance / (1 - (1e-3 / first) ** 2), rel=1e-6)
    assert abs(response["phase"][0]) < 0.1


def finite_difference(document: dict, pointer: str, output: str, step: float) -> float:
    values = []
    for sign in (1, -1):
        mech = compile_mechanism(load_document(document))
        mech = mech.with_values({pointer: mech.value(pointer) + sign * step})
        result = solve_equilibrium(mech)
        assert result.converged
        values.append(outputs_in_doc_units(mech, mech.graphs.outputs(result.z, mech.p()))[output])
    return (values[0] - values[1]) / (2 * step)


def test_the_static_gain_about_a_prestressed_state_equals_finite_differences_of_equilibria():
    """The released rod held at its tip (bending, shear, axial strain, large rotation)."""
    doc = load_document(EXAMPLES / "rod_free_vibration.json").model_dump(by_alias=True, exclude_none=True)
    report = respond(doc, input="/loads/hold/force/1", outputs=["bodies.tip.x", "bodies.tip.y"])
    for output in ("bodies.tip.x", "bodies.tip.y"):
        expected = finite_difference(doc, "/loads/hold/force/1", output, 1e-3)
        assert report["responses"][output]["static"] == pytest.approx(expected, rel=1e-6), output


def test_the_static_gain_of_a_platform_on_a_curved_beam_equals_finite_differences():
    doc = platform_on_a_flexure()
    doc["loads"] = {"push": {"type": "force", "body": "platform", "force": [0.3, 2.0]}}
    report = respond(doc, input="/loads/push/force/1", outputs=["bodies.platform.y", "bodies.platform.angle"])
    for output in ("bodies.platform.y", "bodies.platform.angle"):
        expected = finite_difference(doc, "/loads/push/force/1", output, 1e-4)
        assert report["responses"][output]["static"] == pytest.approx(expected, rel=1e-6), output


@pytest.mark.parametrize(
    "options, pointer, words",
    [
        ({"start": 10, "stop": 5}, "/stop", "the range is empty: stop (5 Hz) must exceed start (10 Hz)"),
        ({"start": -1}, "/start", "greater than 0"),
        ({"input": "/loads/shake/force/7"}, "/input", "not a numeric field"),
        ({"input": "/bodies/carriage/mass"}, "/input", "drives no force on the mechanism"),
        ({"outputs": ["bodies.cart.x"]}, "/outputs/0", "no output 'bodies.cart.x'"),
    ],
)
def test_bad_input_names_the_field(options, pointer, words):
    given = {"input": "/loads/shake/force/0", "outputs": ["bodies.carriage.x"], **options}
    with pytest.raises(MechanismError) as err:
        respond(shaken(), **given)
    assert err.value.pointer == pointer and words in str(err.value)


def test_an_output_of_the_constraints_forces_is_refused_in_the_elements_coordinates():
    doc = strip(2)
    doc["loads"] = {"push": {"type": "force", "body": "tip", "force": [0.0, 0.0]}}
    with pytest.raises(MechanismError) as err:
        respond(doc, input="/loads/push/force/1", outputs=["bodies.tip.y", "reactions.clamp.Fy"], at="undeformed")
    assert err.value.pointer == "/outputs/1" and "moves with the constraints' forces" in str(err.value)


def test_a_load_on_a_massless_body_reaches_it_at_once_and_the_mass_through_the_spring():
    """ground -k2- A (massless, on a rail) -k1- B (mass m, on a rail), the force on A:
    x_B = (k1 F / (k1 + k2)) / (k1 k2 / (k1 + k2) - m omega^2), x_A = (F + k1 x_B) / (k1 + k2)."""
    k1, k2, m = 800.0, 300.0, 0.2
    doc = {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "bodies": {
            "ground": {"fixed": True, "position": [0, 0]},
            "a": {"position": [1, 0]},
            "b": {"position": [2, 0], "mass": m},
        },
        "elements": {
            "rail_a": {"type": "slider", "from": "ground", "to": "a", "angle": 0},
            "rail_b": {"type": "slider", "from": "ground", "to": "b", "angle": 0},
            "k2": {"type": "spring", "from": "ground", "to": "a", "stiffness": k2},
            "k1": {"type": "spring", "from": "a", "to": "b", "stiffness": k1},
        },
        "loads": {"push": {"type": "force", "body": "a", "force": [0.0, 0.0]}},
    }
    report = respond(doc, input="/loads/push/force/0", outputs=["bodies.a.x", "bodies.b.x"], damping_ratio=0)
    omega = 2 * math.pi * np.array(report["frequencies"])
    x_b = (k1 / (k1 + k2)) / (k1 * k2 / (k1 + k2) - m * omega**2)
    x_a = (1 + k1 * x_b) / (k1 + k2)
    assert report["responses"]["bodies.b.x"]["amplitude"] == pytest.approx(np.abs(x_b), rel=1e-9)
    assert report["responses"]["bodies.a.x"]["amplitude"] == pytest.approx(np.abs(x_a), rel=1e-9)
    assert report["responses"]["bodies.a.x"]["static"] == pytest.approx(1 / k2, rel=1e-12)
    assert "undamped" in report["warnings"][-1]


def base_and_mass() -> dict:
    """A 0.3 kg mass on a rail, tied by a 1200 N/m spring to a base whose motion is prescribed."""
    return {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "bodies": {
            "ground": {"fixed": True, "position": [0, 0]},
            "base": {"position": [0, 1]},
            "mass": {"position": [1, 1], "mass": M},
        },
        "elements": {
            "rail": {"type": "slider", "from": "ground", "to": "mass", "angle": 0},
            "coil": {"type": "spring", "from": "base", "to": "mass", "stiffness": K},
        },
        "loads": {"shake": {"type": "displacement", "body": "base", "dx": 0.0, "dy": 0.0, "rotation": 0.0}},
    }


def test_a_shaken_base_moves_a_mass_on_a_spring_as_the_transmissibility_says():
    """Damping on the deformation (the modal ratio): (k + i c omega) / (k - m omega^2 + i c omega),
    c = 2 zeta sqrt(k m); Rayleigh's alpha drags the absolute velocity: k / (k - m omega^2 + i alpha m omega)."""
    zeta, alpha = 0.05, 4.0
    for damping, c_relative, c_absolute in (({"damping_ratio": zeta}, 2 * zeta * math.sqrt(K * M), 0.0),
                                            ({"damping_ratio": 0, "mass_damping": alpha}, 0.0, alpha * M)):  # fmt: skip
        report = respond(base_and_mass(), input="/loads/shake/dx", outputs=["bodies.mass.x"], points=80, **damping)
        omega = 2 * math.pi * np.array(report["frequencies"])
        exact = (K + 1j * c_relative * omega) / (K - M * omega**2 + 1j * (c_relative + c_absolute) * omega)
        response = report["responses"]["bodies.mass.x"]
        assert response["unit"] == "m/m" and response["static"] == pytest.approx(1.0, rel=1e-12)
        assert response["amplitude"] == pytest.approx(np.abs(exact), rel=1e-9)
        assert response["phase"] == pytest.approx(np.degrees(np.angle(exact)), abs=1e-7)


def test_a_cantilever_on_a_shaken_clamp_has_the_tip_transmissibility_of_euler_bernoulli():
    """Tip over base: (cos bL + cosh bL) / (1 + cos bL cosh bL), b^4 = omega^2 rho A / (E I): the
    link's mass rides on the clamp (its inertial coupling) and the end conditions move with it.
    Compared a tenth of a resonance or more away from each, over the first two modes (16 cubic
    elements: near a pole the discretization's shift of it is amplified)."""
    doc = strip(16)
    doc["bodies"]["clamp"] = {"position": [0, 0]}
    doc["loads"] = {"shake": {"type": "displacement", "body": "clamp", "dx": 0, "dy": 0, "rotation": 0}}
    report = respond(
        doc, input="/loads/shake/dy", outputs=["bodies.tip.y"], damping_ratio=0, start=0.01, stop=3, points=60
    )
    E, b, h, L, rho = 2e11, 0.0127, 0.0003, 1.11, 7850.0
    f = np.array(report["frequencies"])
    away = np.all([np.abs(f / r - 1) > 0.1 for r in report["natural_frequencies"] if r], axis=0)
    bl = ((2 * math.pi * f) ** 2 * rho * b * h / (E * b * h**3 / 12)) ** 0.25 * L
    exact = (np.cos(bl) + np.cosh(bl)) / (1 + np.cos(bl) * np.cosh(bl))
    response = report["responses"]["bodies.tip.y"]
    signed = np.array(response["amplitude"]) * np.sign(np.cos(np.radians(response["phase"])))
    assert away.sum() > 25
    assert signed[away] == pytest.approx(exact[away], rel=1e-5)
    assert response["static"] == pytest.approx(1.0, rel=1e-12)


def two_modes(f1: float, f2: float, zeta: float, shares: tuple[float, float]):
    """H(omega) = sum_k share_k / (omega_k^2 - omega^2 + 2 i zeta omega_k omega): two modes,
    one output, no direct part."""
    from flexmech.service.vibration.frf import ModalResponse

    omega = 2 * math.pi * np.array([f1, f2])
    return ModalResponse(
        omega_squared=omega**2,
        participation=np.array([list(shares)]),
        forcing=np.ones(2),
        rates=2 * zeta * omega,
        direct=np.zeros(1),
        inertial=np.zeros(2),
        dragged=np.zeros(2),
    )


def test_a_small_peak_beside_a_larger_mode_is_a_resonance_of_its_own():
    """Two modes 4.6 % apart at zeta = 1 % (the gripper's modes 2 and 3, 7077 and 7401 Hz): the
    larger mode's flank at the edge of the smaller's window (+-4 zeta) is higher than the
    smaller's peak; the peak found is the smaller mode's own local maximum, its frequency and
    height those of the sampled curve."""
    from flexmech.service.vibration.frf import TWO_PI, resonances

    response = two_modes(7077.0, 7401.0, 0.01, (0.6, 4.0))
    peaks = resonances(response, ["elastic", "elastic"], 1000.0, 20000.0)
    assert [p["mode"] for p in peaks] == [1, 2]
    f = np.linspace(6800.0, 7300.0, 200_001)
    curve = np.abs(response.at(TWO_PI * f))[0]
    inner = np.nonzero((curve[1:-1] > curve[:-2]) & (curve[1:-1] > curve[2:]))[0] + 1
    (own,) = inner[np.abs(f[inner] - 7077.0) < 100]  # the curve's one local maximum near mode 1
    assert peaks[0]["frequency"] == pytest.approx(f[own], abs=0.01)
    assert peaks[0]["amplitude"] == pytest.approx(curve[own], rel=1e-9)
    edge = np.abs(response.at(np.array([TWO_PI * 7077.0 * 1.04])))[0, 0]
    assert edge > peaks[0]["amplitude"]  # what hid it: the neighbour's flank in its window


def test_a_mode_drowned_by_its_neighbour_is_listed_at_its_natural_frequency():
    """A mode whose peak a much larger neighbour 2 % away swallows (no local maximum of its
    own) is still in the list: at its natural frequency, the response there, no bandwidth; the
    neighbour's peak is not counted twice."""
    from flexmech.service.vibration.frf import TWO_PI, resonances

    response = two_modes(1000.0, 1020.0, 0.02, (0.01, 10.0))
    peaks = resonances(response, ["elastic", "elastic"], 100.0, 5000.0)
    assert [p["mode"] for p in peaks] == [1, 2]
    drowned, peak = peaks
    assert drowned["frequency"] == pytest.approx(1000.0, rel=1e-12)
    assert drowned["bandwidth"] is None and drowned["quality"] is None
    assert drowned["amplitude"] == pytest.approx(abs(response.at(np.array([TWO_PI * 1000.0]))[0, 0]), rel=1e-12)
    assert peak["frequency"] == pytest.approx(1020.0, rel=1e-3) and peak["bandwidth"] is not None
