"""The state-space model (service.vibration.state_space, issue 29 item 4) against physics: the
Table 4.1 rod's poles are its modes' frequencies and its static gain the Timoshenko cantilever's
compliance; a massless motion's static response is the feedthrough; the python-control system
round-trips through .json, .npz and .mat; `flexmech linearize` writes a .mat MATLAB reads; bad
input is named by its field."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.io
from conftest import EXAMPLES
from test_modes import body_on_springs
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service.analyses import ANALYSES
from flexmech.service.analyses.base import AnalysisRequest
from flexmech.service.solvers.stiffness import tangent_stiffness
from flexmech.service.vibration.frf import Damping
from flexmech.service.vibration.state_space import state_space_model
from flexmech.service.vibration.state_space_files import MATRICES, control_system, read_state_space, write_state_space

ROD = EXAMPLES / "rod_free_vibration.json"
FX, FY = "/loads/hold/force/0", "/loads/hold/force/1"
E, G, B, H, L = 2e11, 8e10, 0.0127, 0.0032, 1.11  # the rod's steel and section
KAPPA = 5 / 6  # models.elements.link: a section without shear_factor
AREA, SECOND = B * H, B * H**3 / 12
BENDING = L**3 / (3 * E * SECOND) + L / (KAPPA * G * AREA)  # m/N, tip y per tip force y
AXIAL = L / (E * AREA)  # m/N, tip x per tip force x
TOLERANCE = 1e-9  # poles and static gains, relative (issue 29, acceptance 5)


@pytest.fixture(scope="module")
def rod():
    return compile_mechanism(load_document(ROD))


@pytest.fixture(scope="module")
def rod_model(rod):
    return state_space_model(rod, None, [FX, FY], ["bodies.tip.x", "bodies.tip.y"])


def test_the_rods_poles_are_its_modes_and_its_static_gain_the_timoshenko_cantilevers(rod, rod_model):
    """About the undeformed state. The poles: eig(A) itself, against the modes analysis' 72
    frequencies (measured: 2e-16). The static gain -C A^-1 B + D against K_T^-1 (the residual
    form's tangent stiffness, inverted) and against the Timoshenko cantilever,

        y / Fy = L^3 / (3 E I) + L / (kappa G A),   x / Fx = L / (E A),

    kappa = 5/6 (the shear term is 6.2e-6 of the bending one). The link's rotations are cubic
    per element and its strains quadratic, so the discrete cantilever is exact under a tip load
    (measured: 1.4e-12 and 6e-16 from the formulas; K_T^-1 within 1.5e-12)."""
    modes = ANALYSES.named("modes").run(rod, AnalysisRequest(given={"count": 72, "at": "undeformed", "shapes": False}))
    expected = np.array([mode["frequency"] for mode in modes["modes"]])
    poles = np.linalg.eigvals(rod_model.A)
    assert np.abs(poles.real).max() < 1e-9 * np.abs(poles).min()  # undamped
    found = np.sort(poles.imag[poles.imag > 0]) / (2 * math.pi)
    assert found.shape == expected.shape == (72,)
    np.testing.assert_allclose(found, expected, rtol=TOLERANCE)
    np.testing.assert_allclose(np.sort(rod_model.poles.imag), np.sort(poles.imag), rtol=1e-12, atol=1e-9)
    gain = rod_model.static_gain
    assert rod_model.units["inputs"] == ["N", "N"] and rod_model.units["outputs"] == ["m", "m"]
    compliance = np.linalg.inv(tangent_stiffness(rod).K)[:2, :2]  # tip x, y per Fx, Fy (m/N)
    np.testing.assert_allclose(np.diag(gain), np.diag(compliance), rtol=TOLERANCE)
    assert gain[1, 1] == pytest.approx(BENDING, rel=TOLERANCE) and gain[0, 0] == pytest.approx(AXIAL, rel=TOLERANCE)
    assert abs(gain[0, 1]) + abs(gain[1, 0]) < 1e-12 * gain[1, 1]  # straight: bending and stretching uncoupled
    assert -rod_model.C @ np.linalg.solve(rod_model.A, rod_model.B) + rod_model.D == pytest.approx(gain, rel=1e-9)


def test_about_the_equilibrium_the_static_gain_is_the_tangent_compliance_there(rod):
    """The rod held bent by its hold force (prestress and large rotation): measured 1e-13."""
    from flexmech.service.solvers.equilibrium import solve_equilibrium

    report = ANALYSES.named("linearization").run(
        rod, AnalysisRequest(given={"state_space": {"inputs": [FX, FY], "outputs": ["bodies.tip.x", "bodies.tip.y"]}})
    )
    compliance = np.linalg.inv(tangent_stiffness(rod, solve_equilibrium(rod).z).K)[:2, :2]
    np.testing.assert_allclose(report["state_space"]["static_gain"], compliance, rtol=1e-9)


def test_the_lowest_modes_keep_the_static_gain_and_damping_places_the_poles(rod, rod_model):
    zeta = 0.05
    low = state_space_model(rod, None, [FX, FY], ["bodies.tip.x", "bodies.tip.y"], Damping(ratio=zeta), modes=4)
    assert low.A.shape == (8, 8) and low.states[:2] == ["mode1", "mode2"] and low.states[4] == "mode1_rate"
    np.testing.assert_allclose(low.static_gain, rod_model.static_gain, rtol=1e-12, atol=1e-20)
    omega = np.sqrt(-np.diag(rod_model.A[72:, :72])[:4])
    upper = low.poles[low.poles.imag > 0]
    upper = upper[np.argsort(upper.imag)]
    np.testing.assert_allclose(upper.real, -zeta * omega, rtol=1e-12)
    np.testing.assert_allclose(upper.imag, omega * math.sqrt(1 - zeta**2), rtol=1e-12)


def test_a_massless_rotation_answers_its_moment_at_once_through_d():
    """A wheel without inertia on a torsion spring follows its moment statically: 1/kt in D,
    nothing in C; the carriage is the one mode, sqrt(k/m). Without its spring the carriage is
    free: a rigid mode, double zero poles, and no static gain."""
    m, k, kt = 0.3, 1200.0, 4.5
    doc = body_on_springs(m, 0.0, k, kt)
    del doc["bodies"]["wheel"]["inertia"]
    doc["loads"] = {
        "push": {"type": "force", "body": "carriage", "force": [0, 0]},
        "turn": {"type": "moment", "body": "wheel", "moment": 0},
    }
    mech = compile_mechanism(load_document(doc))
    model = state_space_model(mech, None, None, ["bodies.carriage.x", "bodies.wheel.angle"])
    assert model.inputs == ["/loads/push/force/0", "/loads/push/force/1", "/loads/turn/moment"]
    assert model.A.shape == (2, 2) and np.sort(model.poles.imag) == pytest.approx([-math.sqrt(k / m), math.sqrt(k / m)])
    np.testing.assert_allclose(model.static_gain, [[1 / k, 0, 0], [0, 0, 1 / kt]], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(model.D, [[0, 0, 0], [0, 0, 1 / kt]], rtol=1e-12, atol=1e-12 / k)
    del doc["elements"]["coil"]
    free = state_space_model(compile_mechanism(load_document(doc)), None, None, ["bodies.wheel.angle"])
    assert free.kinds == ["rigid"] and np.all(free.poles == 0) and free.static_gain is None
    assert free.D[0, 2] == pytest.approx(1 / kt, rel=1e-12)


def test_the_python_control_system_round_trips_through_every_file(rod, rod_model, tmp_path):
    import control

    system = control_system(rod_model)
    assert system.output_labels == ["bodies_tip_x", "bodies_tip_y"] and system.ninputs == 2 and system.nstates == 144
    np.testing.assert_allclose(np.sort(system.poles().imag), np.sort(rod_model.poles.imag), rtol=1e-12, atol=1e-9)
    compliance = np.linalg.inv(tangent_stiffness(rod).K)[:2, :2]
    np.testing.assert_allclose(np.diag(control.dcgain(system)), np.diag(compliance), rtol=TOLERANCE)
    for suffix in (".json", ".npz", ".mat"):
        path = tmp_path / f"rod{suffix}"
        write_state_space(rod_model, path)
        back = read_state_space(path)
        for name in MATRICES:
            np.testing.assert_array_equal(getattr(back, name), getattr(rod_model, name), err_msg=f"{suffix} {name}")
        assert (back.states, back.inputs, back.outputs, back.units, back.kinds) == (
            rod_model.states,
            rod_model.inputs,
            rod_model.outputs,
            rod_model.units,
            rod_model.kinds,
        ), suffix
        again = control_system(back)
        np.testing.assert_array_equal(again.A, system.A)
        np.testing.assert_array_equal(control.dcgain(again), control.dcgain(system))


def test_flexmech_linearize_writes_a_mat_file_matlab_reads_and_names_a_bad_output(tmp_path):
    from flexmech.api.cli.linearize import SUFFIXES
    from flexmech.service.vibration import state_space_files

    assert SUFFIXES == state_space_files.SUFFIXES
    out = tmp_path / "rod.mat"
    args = ["linearize", str(ROD), "--at", "undeformed", "--input", FY, "--output", "bodies.tip.y", "--modes", "3"]
    result = CliRunner().invoke(app, [*args, "--state-space", str(out)], env={"COLUMNS": "200", "NO_COLOR": "1"})
    assert result.exit_code == 0, result.output
    assert (
        "2.11769" in result.output and "65.7276 mm/N" in result.output
    )  # the first mode (Hz), the static gain (0.0657 m/N in mm/N, service.display)
    mat = scipy.io.loadmat(out)
    shapes = {name: mat[name].shape for name in ("A", "B", "C", "D", "M", "K", "Dmp", "Phi", "poles", "static_gain")}
    assert shapes == {
        "A": (6, 6), "B": (6, 1), "C": (1, 6), "D": (1, 1), "M": (75, 75), "K": (75, 75), "Dmp": (75, 75),
        "Phi": (75, 3), "poles": (1, 6), "static_gain": (1, 1),
    }  # fmt: skip
    assert [str(cell[0]) for cell in mat["outputs"].ravel()] == ["bodies.tip.y"]
    assert mat["static_gain"][0, 0] == pytest.approx(BENDING, rel=TOLERANCE)
    wrong = CliRunner().invoke(app, [*args[:-4], "--output", "bodies.tip.q"])
    assert wrong.exit_code == 2 and "error: --output: no output 'bodies.tip.q'" in wrong.stderr


def test_bad_input_is_named_by_its_field(rod):
    def linearize(document, **state_space):
        return ANALYSES.named("linearization").run(
            document, AnalysisRequest(given={"at": "undeformed", "state_space": state_space})
        )

    for state_space, pointer, words in (
        ({"outputs": ["bodies.tip.q"]}, "/state_space/outputs/0", "no output 'bodies.tip.q'"),
        ({"inputs": [FY, "/loads/hold/force/2"]}, "/state_space/inputs/1", "not a numeric field"),
        ({"modes": 73}, "/state_space/modes", "73 modes asked, but the mechanism has 72"),
        ({"outputs": []}, "/state_space/outputs", "at least 1 item"),
    ):
        with pytest.raises(MechanismError) as err:
            linearize(rod, **state_space)
        assert err.value.pointer == pointer and words in err.value.problem


def test_the_massless_gripper_is_its_static_response_about_its_operating_point(tmp_path):
    """Seed 000's gripper has no mass: its linear model for a controller is D alone, the jaw's
    response to the actuation force about the equilibrium under 50 uN. It equals central
    differences of flexmech's own equilibrium (+-0.01 uN) to 1e-7, and python-control takes it
    as a static gain."""
    from flexmech.service.solvers.equilibrium import solve_equilibrium
    from flexmech.service.solvers.newton import NewtonOptions

    mech = compile_mechanism(load_document(EXAMPLES / "gripper.json"))
    force, outputs = "/loads/actuation/force/1", ["end_effector.x", "end_effector.y"]
    operating = solve_equilibrium(mech, NewtonOptions())
    model = state_space_model(mech, operating.z, [force], outputs)
    assert model.A.shape == (0, 0) and model.B.shape == (0, 1) and model.C.shape == (2, 0) and model.states == []
    moved = []
    for value in (50.01, 49.99):
        found = solve_equilibrium(mech.with_values({force: value}), NewtonOptions()).outputs()
        moved.append([found[name] for name in outputs])
    expected = (np.array(moved[0]) - np.array(moved[1])) / 0.02
    assert np.allclose(model.D[:, 0], expected, rtol=1e-7, atol=0)
    assert model.units["inputs"] == ["uN"] and model.units["outputs"] == ["mm", "mm"]
    path = tmp_path / "gripper.mat"
    write_state_space(model, path)
    assert np.array_equal(read_state_space(path).D, model.D)
    assert np.allclose(np.asarray(control_system(model).dcgain()).reshape(model.D.shape), model.D, rtol=1e-12)
    with pytest.raises(MechanismError) as no_modes:
        state_space_model(mech, operating.z, [force], outputs, modes=2)
    assert no_modes.value.pointer == "/state_space/modes" and "no mass" in no_modes.value.problem
