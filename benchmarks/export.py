"""The exported C library of the gripper (issue 29), side by side with flexmech's own warm
solves in Python, in one run.

For each curved-beam model (linear, partial_nonlinear, exact):
  export       writing the library (code generation, no compiler), and the kernels' C size
  compile      `make` with gcc -std=c99 -O2 -Wall -Wextra -Werror: wall time and the compiler's
               peak memory (the largest child)
  C warm       ./bench: a 100-point sweep of the actuation force to the closing force, back and
               forth, each call from its neighbour's solution (time per call, Newton steps)
  C cold       the same points, each call from undeformed
  py newton    flexmech's Newton (service.solvers.equilibrium.newton), warm, per point
  py fastpath  flexmech's compiled fast path (FastPath.solve: Newton inside CasADi, called once
               per point from Python), warm, per point
Each timing is the best of 3, the two sides run alternately. The same physics on both sides:
the same model, unknowns and sweep; the closing force from the
C target task and from flexmech's solve_for_target, and the largest difference of the outputs
over the sweep (relative to each output's largest magnitude). The peer is flexmech itself (no
install); the C side needs gcc and make (scripts/c-tools-for-tests installs them). Run from the
repository root:

    python3 -m benchmarks.export [--rounds 50] [--models linear,partial_nonlinear,exact]
"""

from __future__ import annotations

import argparse
import importlib.util
import re
import resource
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from flexmech.models import compile_mechanism, load_document
from flexmech.service.export.library import export_document
from flexmech.service.export.plan import ExportOptions
from flexmech.service.solvers.equilibrium import newton
from flexmech.service.solvers.fastpath import FastPath
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.sweep import solve_for_target, sweep

ROOT = Path(__file__).resolve().parents[1]
FORCE = "/loads/actuation/force/1"
FLAGS = "-std=c99 -O2 -Wall -Wextra -Werror"
REPEATS = 3


def _compile(folder: Path) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    started = time.perf_counter()
    subprocess.run(["make", "-s", "-C", str(folder), f"CFLAGS={FLAGS}", "all"], check=True, capture_output=True)
    seconds = time.perf_counter() - started
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return seconds, max(peak, before) / 1024  # MiB (ru_maxrss is in kB; the largest child so far)


def _bench(folder: Path, rounds: int) -> dict[str, tuple[float, float]]:
    text = subprocess.run([str(folder / "bench"), str(rounds)], check=True, capture_output=True, text=True).stdout
    found = {}
    for kind, us, steps in re.findall(r"equilibrium (warm|cold): ([\d.]+) us per call \(([\d.]+) Newton", text):
        found[kind] = (float(us), float(steps))
    return found


def _loader(folder: Path, model: str):
    spec = importlib.util.spec_from_file_location(f"bench_loader_{model}", folder / "loader.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.Solver()


def _python_warm(mech, values: np.ndarray, rounds: int) -> tuple[float, float]:
    """Seconds per point of flexmech's Newton and of its compiled fast path, warm, over the sweep
    back and forth."""
    k = mech.parameter_index(FORCE)
    factor = mech.nd_per_doc("force")
    path = list(values) + list(values[::-1])
    fast = FastPath(mech)
    p = mech.p()
    z = np.zeros(mech.n_free)
    started = time.perf_counter()
    for _ in range(max(1, rounds // 10)):
        for v in path:
            p[k] = v * factor
            z = newton(mech, p, z, NewtonOptions()).z
    per_newton = (time.perf_counter() - started) / (max(1, rounds // 10) * len(path))
    z = np.zeros(mech.n_free)
    fast.solve(p, z)  # the first call binds its buffers
    started = time.perf_counter()
    for _ in range(rounds // 2):
        for v in path:
            p[k] = v * factor
            z, _ = fast.solve(p, z)
    per_fast = (time.perf_counter() - started) / ((rounds // 2) * len(path))
    return per_newton, per_fast


def row(model: str, rounds: int, scratch: Path) -> None:
    document = load_document(ROOT / "examples" / "gripper.json")
    folder = scratch / model
    started = time.perf_counter()
    manifest = export_document(document, folder, model, ExportOptions(name=f"gripper_{model[:3]}"))
    export_seconds = time.perf_counter() - started
    c_kb = (folder / f"gripper_{model[:3]}_kernels.c").stat().st_size / 1e3
    compile_seconds, peak = _compile(folder)
    mech = compile_mechanism(document, model)
    plan = manifest["example_path"]
    (moved,) = plan["inputs"]
    values = np.linspace(moved["start"], moved["stop"], plan["points"])
    reference = sweep(mech, FORCE, values)
    solver = _loader(folder, model)
    worst = 0.0
    for i, v in enumerate(values):
        _, outputs, _ = solver.equilibrium(actuation_force_y=v)
        for name in solver.output_names:
            scale = np.abs(reference.outputs[name]).max() or 1.0  # an output that stays 0: absolute
            worst = max(worst, abs(outputs[name] - reference.outputs[name][i]) / scale)
    c_force = solver.target(goal=0.0)[1]
    py_force = solve_for_target(mech, FORCE, "end_effector.x", 0.0).value
    # both sides alternately, REPEATS times, the best of each (a shared machine's noise is one-sided)
    runs = [(_bench(folder, rounds), _python_warm(mech, values, rounds)) for _ in range(REPEATS)]
    c = {kind: min((r[0][kind] for r in runs), key=lambda item: item[0]) for kind in ("warm", "cold")}
    per_newton, per_fast = min(r[1][0] for r in runs), min(r[1][1] for r in runs)
    print(
        f"{model:18s} unknowns {manifest['unknowns']:4d} | export {export_seconds:5.2f} s, kernels C {c_kb:6.0f} kB, "
        f"compile {compile_seconds:5.1f} s, peak {peak:5.0f} MiB"
    )
    print(
        f"{'':18s} C warm {c['warm'][0]:8.2f} us ({c['warm'][1]:.2f} steps) | C cold {c['cold'][0]:8.2f} us "
        f"({c['cold'][1]:.2f} steps) | py newton warm {1e6 * per_newton:8.1f} us ({per_newton * 1e6 / c['warm'][0]:.0f}x C) "
        f"| py fastpath warm {1e6 * per_fast:7.1f} us ({per_fast * 1e6 / c['warm'][0]:.1f}x C)"
    )
    print(
        f"{'':18s} closing force C {c_force:.6f} uN, flexmech {py_force:.6f} uN (rel. diff {abs(c_force - py_force) / py_force:.1e}); "
        f"outputs over the sweep: largest diff {worst:.1e} of their range; worst Newton steps (manifest) "
        f"warm {manifest['worst_case_iterations']['equilibrium_warm']}, cold {manifest['worst_case_iterations']['equilibrium_cold']}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=50, help="sweeps back and forth per timing")
    parser.add_argument("--models", default="linear,partial_nonlinear,exact")
    args = parser.parse_args()
    print(f"gripper (examples/gripper.json), 100-point sweep of the actuation force; C built with gcc {FLAGS}")
    with tempfile.TemporaryDirectory() as scratch:
        for model in args.models.split(","):
            row(model, args.rounds, Path(scratch))


if __name__ == "__main__":
    main()
