"""The exported C library of the gripper (issue 29): built with the strict flags, it gives
flexmech's own equilibrium, stiffness and closing forces, allocates nothing, is re-entrant and
survives a NaN input. The library is loaded through the loader it ships (ctypes)."""

from __future__ import annotations

import importlib.util
import subprocess

import numpy as np
import pytest
from c_tools import ensure_c_tools
from conftest import EXAMPLES

from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service.export.library import export_document
from flexmech.service.export.plan import ExportOptions
from flexmech.service.solvers.stiffness import tangent_stiffness
from flexmech.service.solvers.sweep import solve_for_target, sweep


@pytest.fixture(scope="module", autouse=True)
def c_tools():
    ensure_c_tools()


STRICT = "-std=c99 -O2 -Wall -Wextra -Werror"  # the flags, also the Makefile's own
CLOSING_FORCE = {"linear": 63.9469, "partial_nonlinear": 77.0346, "exact": 69.8573}  # uN, README and seed 000
FORCE = "/loads/actuation/force/1"


def _built(folder, model: str, targets: tuple[str, ...] = ("all",)) -> subprocess.CompletedProcess:
    export_document(load_document(EXAMPLES / "gripper.json"), folder, model, ExportOptions(name=f"gripper_{model[:3]}"))
    return subprocess.run(
        ["make", "-C", str(folder), f"CFLAGS={STRICT}", "CC=gcc", *targets],
        capture_output=True,
        text=True,
        timeout=600,
    )


def _solver(folder, model: str):
    spec = importlib.util.spec_from_file_location(f"loader_{model}", folder / "loader.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.Solver()


@pytest.fixture(scope="module", params=["linear", "partial_nonlinear", "exact"])
def library(request, tmp_path_factory):
    model = request.param
    folder = tmp_path_factory.mktemp(f"export_{model}")
    done = _built(folder, model, ("all", "check"))
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return model, folder, done.stdout


def test_the_library_compiles_with_strict_warnings_and_its_sweep_equals_flexmechs(library):
    """100 points of the actuation force up to the closing force: every output equals
    flexmech's own sweep to 1e-10 of its largest magnitude over the sweep (end_effector.x
    passes through zero at the last point, where a pointwise ratio means nothing)."""
    model, folder, _ = library
    solver = _solver(folder, model)
    plan = solver.manifest["example_path"]
    (moved,) = plan["inputs"]
    assert plan["points"] == 100 and moved["name"] == "actuation_force_y"
    values = np.linspace(moved["start"], moved["stop"], plan["points"])
    mech = compile_mechanism(load_document(EXAMPLES / "gripper.json"), model)
    reference = sweep(mech, FORCE, values)
    assert all(s == "converged" for s in reference.status)
    rows = []
    for v in values:
        status, outputs, iterations = solver.equilibrium(actuation_force_y=v)
        assert status == 0 and iterations <= solver.manifest["worst_case_iterations"]["equilibrium_warm"]
        rows.append([outputs[name] for name in solver.output_names])
    found = np.array(rows)
    for j, name in enumerate(solver.output_names):
        expected = reference.outputs[name]
        assert np.abs(found[:, j] - expected).max() <= 1e-10 * np.abs(expected).max(), name


def test_the_stiffness_task_equals_the_tangent_stiffness(library):
    model, folder, _ = library
    solver = _solver(folder, model)
    mech = compile_mechanism(load_document(EXAMPLES / "gripper.json"), model).with_values({FORCE: 40.0})
    reference = sweep(mech, FORCE, [40.0])
    status, K = solver.stiffness(actuation_force_y=40.0)
    assert status == 0
    expected = tangent_stiffness(mech, reference.z[0]).K
    assert np.abs(np.array(K) - expected).max() <= 1e-9 * np.abs(expected).max()


def test_the_target_task_gives_the_closing_forces(library):
    model, folder, _ = library
    solver = _solver(folder, model)
    status, force, outputs, iterations = solver.target(goal=0.0)
    assert status == 0, solver.status_text(status)
    assert round(force, 4) == CLOSING_FORCE[model]
    mech = compile_mechanism(load_document(EXAMPLES / "gripper.json"), model)
    assert force == pytest.approx(solve_for_target(mech, FORCE, "end_effector.x", 0.0).value, rel=1e-10)
    assert abs(outputs["end_effector.x"]) < 1e-12
    assert iterations <= solver.manifest["worst_case_iterations"]["target_cold"]
    # warm: a second call starts at the solution and takes no step
    assert solver.target(goal=0.0)[3] == 0


def test_the_shipped_checks_pass_no_allocation_nan_and_two_threads(library):
    """check.c (make check) wraps malloc/calloc/realloc/free at link time and counts them
    during 401 calls (every task at 100 points, and the NaN call), after proving the counter sees a deliberate allocation; a NaN input gives
    BAD_INPUT and the struct then gives, to the bit, what a struct that never saw it gives; two
    threads with their own structs give, to the bit, what one thread gives."""
    _, _, log = library
    assert "a deliberate malloc and free while counting: 2 calls seen" in log
    assert "allocations during 401 calls: 0 (0 failed calls)" in log
    assert "NaN input: status 2 (an input is NaN or infinite)" in log
    assert "after the NaN call the struct gives the results of one that never saw it: yes" in log
    assert log.count("with its own work struct equals one thread: yes") == 2
    assert "check: PASS" in log


def test_the_library_calls_no_allocator_and_no_io(library):
    """What the library's objects leave undefined: math only (no malloc, free, printf, files)."""
    model, folder, _ = library
    name = f"gripper_{model[:3]}"
    undefined, defined = set(), set()
    for obj in (f"{name}.o", f"{name}_kernels.o"):
        for flag, into in (("-u", undefined), ("--defined-only", defined)):
            listing = subprocess.run(["nm", flag, str(folder / obj)], capture_output=True, text=True, check=True).stdout
            into |= {line.split()[-1] for line in listing.splitlines() if line.strip()}
    undefined -= defined  # the driver calls the kernels
    assert undefined, "nm lists the math the kernels call"
    allowed = {
        "sqrt",
        "sin",
        "cos",
        "atan2",
        "fabs",
        "fmax",
        "fmin",
        "pow",
        "exp",
        "log",
        "tan",
        "asin",
        "acos",
        "atan",
        "floor",
        "ceil",
        "memcpy",
        "memset",
        "_GLOBAL_OFFSET_TABLE_",
        "sincos",
        "copysign",
        "cosh",
        "sinh",
        "tanh",
        "expm1",
        "log1p",
    }
    assert {s.split("@")[0] for s in undefined} <= allowed, sorted(undefined)


def test_nan_and_out_of_range_inputs_return_their_status_and_leave_the_struct_usable(tmp_path):
    """Through the loader: NaN -> BAD_INPUT, a value outside a --range -> OUT_OF_RANGE, then the
    same struct solves as before."""
    folder = tmp_path / "ranged"
    options = ExportOptions(name="ranged", ranges={FORCE: (-100.0, 100.0)})
    export_document(load_document(EXAMPLES / "gripper.json"), folder, "linear", options)
    done = subprocess.run(["make", "-C", str(folder), "libranged.so"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    solver = _solver(folder, "ranged")
    first = solver.equilibrium(actuation_force_y=30.0)
    assert solver.equilibrium(actuation_force_y=float("nan"))[0] == 2
    assert solver.equilibrium(actuation_force_y=150.0)[0] == 3
    assert solver.status_text(3) == "an input is outside its range"
    again = solver.equilibrium(actuation_force_y=30.0)
    assert again[0] == 0 and again[1] == first[1] and again[2] == 0  # the kept solution: no step


def test_export_choices_are_checked_and_named(tmp_path):
    mech_doc = load_document(EXAMPLES / "gripper.json")
    with pytest.raises(MechanismError) as bad_output:
        export_document(mech_doc, tmp_path / "a", "linear", ExportOptions(outputs=("end_effector.z",)))
    assert bad_output.value.pointer == "/outputs/0" and "unknown output 'end_effector.z'" in str(bad_output.value)
    with pytest.raises(MechanismError) as bad_input:
        export_document(mech_doc, tmp_path / "b", "linear", ExportOptions(inputs=("/loads/actuation/force/7",)))
    assert bad_input.value.pointer == "/inputs/0"
    with pytest.raises(MechanismError) as bad_range:
        export_document(mech_doc, tmp_path / "c", "linear", ExportOptions(ranges={"/sections/flexure/h": (1, 2)}))
    assert bad_range.value.pointer == "/ranges//sections/flexure/h" and "not an exported input" in str(bad_range.value)
    with pytest.raises(MechanismError) as free:  # a linkage's free motion has no static equilibrium
        export_document(load_document(EXAMPLES / "four_bar_dynamics.json"), tmp_path / "e", None, ExportOptions())
    assert free.value.pointer == "/bodies" and "under-constrained" in free.value.problem
    with pytest.raises(MechanismError) as narrow:
        export_document(mech_doc, tmp_path / "d", "linear", ExportOptions(ranges={FORCE: (0.0, 100.0)}))
    assert narrow.value.pointer == f"/ranges/{FORCE}" and "from -60 to 63.94690" in narrow.value.problem
    assert not (tmp_path / "a").exists()


def test_the_cmake_build_runs_the_checks(tmp_path):
    """The CMakeLists.txt builds the library, example, benchmark and checks; ctest runs the checks."""
    source, build = tmp_path / "src", tmp_path / "build"
    export_document(load_document(EXAMPLES / "gripper.json"), source, "linear", ExportOptions(name="gripper"))
    for command in (["cmake", "-S", str(source), "-B", str(build)], ["cmake", "--build", str(build), "-j2"]):
        done = subprocess.run(command, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    tested = subprocess.run(["ctest", "--output-on-failure"], cwd=build, capture_output=True, text=True, timeout=300)
    assert tested.returncode == 0 and "100% tests passed" in tested.stdout, tested.stdout[-2000:]
    example = subprocess.run([str(build / "gripper_example")], capture_output=True, text=True, timeout=60, check=True)
    assert "target: end_effector.x = 0 mm at actuation_force_y = 63.94690" in example.stdout


def test_without_a_sweep_the_example_path_applies_the_documents_loads(tmp_path):
    """The rod has no sweep: its example ramps both hold-force components from 0 to their
    document values together, and the manifest says so."""
    manifest = export_document(
        load_document(EXAMPLES / "rod_free_vibration.json"), tmp_path / "rod", None, ExportOptions()
    )
    moved = {item["name"]: (item["start"], item["stop"]) for item in manifest["example_path"]["inputs"]}
    assert moved == {"hold_force_x": (0.0, 7.919276), "hold_force_y": (0.0, 10.998155)}
    assert manifest["worst_case_iterations"]["failed_points"] == 0


def test_a_mechanism_without_outputs_or_free_bodies_exports_its_reactions_and_compiles(tmp_path):
    """grasper_shape names no outputs and holds or moves both its bodies: its export's outputs
    are the bodies' reactions (before, none: zero-length arrays that gcc refused), it builds with
    the strict flags, and its reactions at the full push equal flexmech's own."""
    folder = tmp_path / "grasper"
    manifest = export_document(load_document(EXAMPLES / "grasper_shape.json"), folder, None, ExportOptions())
    reactions = [f"reactions.{body}.{part}" for body in ("base", "tip") for part in ("Fx", "Fy", "M")]
    assert [output["output"] for output in manifest["outputs"]] == reactions
    done = subprocess.run(
        ["make", "-C", str(folder), f"CFLAGS={STRICT}", "CC=gcc", "all"], capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    solver = _solver(folder, "grasper")
    status, outputs, _ = solver.equilibrium(push_dy=0.0127)
    reference = sweep(
        compile_mechanism(load_document(EXAMPLES / "grasper_shape.json"), None), "/loads/push/dy", [0.0127]
    )
    assert status == 0 and reference.status == ["converged"]
    found = dict(zip(reactions, (outputs[name] for name in solver.output_names)))
    for name in reactions:
        assert found[name] == pytest.approx(reference.outputs[name][0], rel=1e-10, abs=1e-12), name
    assert found["reactions.tip.Fy"] == pytest.approx(-found["reactions.base.Fy"], rel=1e-9)  # balanced
    assert found["reactions.tip.Fy"] > 0.5  # N: a push of 12.7 mm takes a force (not a zero passing)
