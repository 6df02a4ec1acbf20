"""How fast link dynamics can be on its own kernels: the arithmetic floor of a time step,
beside the measured run and the peer (issue 23, acceptance 1).

A step of the kernel core (service.dynamics.kernel_window) evaluates the residual once and
then once per Newton iteration (the forward sweep over the elements, the backward sweep over
the blocks), solves once per iteration (the substitution sweep), and factors the Newton system
once per window (every element's Jacobian, the factor sweep). The floor is that work alone:

    floor per step = (iterations + 1) E + iterations S + (factorizations / steps) F

with E, S, F the time of the element kernels themselves (models.kernels: sweep, backward,
substitute, jacobian, factor), each generated as C by CasADi, compiled with gcc -O2 and timed in
a C loop (at least 0.3 s of calls, best of three), without any glue, copying or Python; the
counts are those of a real warm run. It is what a step would cost if everything around the
kernels were free.

Printed per shipped example: each kernel's microseconds per call, the floor per simulated
second, flexmech's measured warm run, the peer model that reaches flexmech's accuracy (as
benchmarks.dynamics finds it: the rod's period to 1e-3, the four-bar's energy balance), and
the 2x target of issue 23. The rod is then run with fewer cubic elements, to show its period
error and cost at the peer's accuracy.

The peer: pip install "flexmech[bench]" (exudyn); gcc. Run from the repository root:

    python3 -m benchmarks.dynamics_floor
"""

from __future__ import annotations

import os
import subprocess
import tempfile
from pathlib import Path

import numpy as np

KERNELS = ("sweep", "backward", "substitute", "jacobian", "factor")
TIMED_SECONDS = 0.3  # per kernel and repetition


def kernel_functions(signature) -> dict:
    """The single-item kernels of a chain signature, by name."""
    from flexmech.models.kernels.chain_solver import solver_functions
    from flexmech.models.kernels.chain_sweep import sweep_function
    from flexmech.models.kernels.link_chain import jacobian_function

    solver = solver_functions(signature)
    return {
        "sweep": sweep_function(signature),
        "backward": solver.backward,
        "substitute": solver.substitute,
        "jacobian": jacobian_function(signature),
        "factor": solver.factor,
    }


def _harness(functions: dict) -> str:
    """A C main that times each kernel on inputs in [0.5, 1.5] (no denormals, moderate
    angles), best of three, and prints 'name microseconds finite'."""
    lines = [
        "#include <math.h>",
        "#include <stdio.h>",
        "#include <stdlib.h>",
        "#include <time.h>",
        "typedef long long int casadi_int;",
        "static double now(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t);"
        " return t.tv_sec + 1e-9 * t.tv_nsec; }",
    ]
    for fn in functions.values():
        lines.append(f"int {fn.name()}(const double** arg, double** res, casadi_int* iw, double* w, int mem);")
        lines.append(f"int {fn.name()}_work(casadi_int*, casadi_int*, casadi_int*, casadi_int*);")
    lines.append("int main(void) {")
    for name, fn in functions.items():
        n_in, n_out = sum(fn.nnz_in(i) for i in range(fn.n_in())), sum(fn.nnz_out(i) for i in range(fn.n_out()))
        lines += [
            "{",
            f"  casadi_int sa, sr, siw, sw; {fn.name()}_work(&sa, &sr, &siw, &sw);",
            f"  double *in = malloc({n_in + 1} * sizeof(double)), *out = malloc({n_out + 1} * sizeof(double));",
            "  double *w = malloc((sw + 1) * sizeof(double)); casadi_int *iw = malloc((siw + 1) * sizeof(casadi_int));",
            f"  for (int i = 0; i < {n_in}; i++) in[i] = 0.5 + (double)((i * 7919) % 1000) / 1000.0;",
            f"  const double *arg[{fn.n_in() + 1}]; double *res[{fn.n_out() + 1}];",
        ]
        offset = 0
        for i in range(fn.n_in()):
            lines.append(f"  arg[{i}] = in + {offset};")
            offset += fn.nnz_in(i)
        offset = 0
        for i in range(fn.n_out()):
            lines.append(f"  res[{i}] = out + {offset};")
            offset += fn.nnz_out(i)
        lines += [
            "  long calls = 1000; double best = 1e300;",
            f"  for (;;) {{ double t0 = now(); for (long c = 0; c < calls; c++) {fn.name()}(arg, res, iw, w, 0);",
            f"    if (now() - t0 > {TIMED_SECONDS}) break; calls *= 2; }}",
            "  for (int r = 0; r < 3; r++) { double t0 = now();",
            f"    for (long c = 0; c < calls; c++) {fn.name()}(arg, res, iw, w, 0);",
            "    double t = (now() - t0) / calls; if (t < best) best = t; }",
            f"  int finite = 1; for (int i = 0; i < {n_out}; i++) finite &= isfinite(out[i]) != 0;",
            f'  printf("{name} %.4f %d\\n", 1e6 * best, finite);',
            "}",
        ]
    lines += ["return 0;", "}"]
    return "\n".join(lines)


def time_kernels(signature) -> dict[str, float]:
    """Microseconds per call of each kernel of the signature (compiled -O2, called from C)."""
    import casadi as ca

    functions = kernel_functions(signature)
    with tempfile.TemporaryDirectory() as tmp:
        sources = []
        for name, fn in functions.items():
            generator = ca.CodeGenerator(f"{name}.c", {"with_header": False, "casadi_int": "long long int"})
            generator.add(fn)
            generator.generate(f"{tmp}/")
            sources.append(f"{name}.c")
        Path(tmp, "main.c").write_text(_harness(functions))
        subprocess.run(
            ["gcc", "-O2", "-o", "timer", "main.c", *sources, "-lm"], check=True, capture_output=True, cwd=tmp
        )
        printed = subprocess.run(["./timer"], check=True, capture_output=True, text=True, cwd=tmp).stdout
    timings = {}
    for row in printed.strip().splitlines():
        name, micro, finite = row.split()
        if finite != "1":
            raise RuntimeError(f"the {name} kernel gave a non-finite output on the timing inputs")
        timings[name] = float(micro)
    return timings


def counted_run(mech, until: float) -> tuple[dict, int, float]:
    """(the warm run's report, its number of windows: factorizations, seconds of compiling its
    kernels and window first)."""
    from benchmarks.dynamics import compile_kernels, flexmech_run
    from flexmech.service.dynamics.engine import _engines
    from flexmech.service.dynamics.run import run_simulation, simulation_spec
    from flexmech.service.dynamics.stepping import StepRunner

    compiled = compile_kernels(mech)
    _engines.clear()
    flexmech_run(mech, until=0.02)  # the engine built on the compiled kernels
    windows = [0]
    original = StepRunner.run_window

    def counting(self, *args, **kwargs):
        windows[0] += 1
        return original(self, *args, **kwargs)

    StepRunner.run_window = counting
    try:
        _, report = run_simulation(mech, simulation_spec(mech, {"until": until, "every": 1}))
    finally:
        StepRunner.run_window = original
    return report, windows[0], compiled


def floor_row(mech, until: float) -> dict:
    """The example's kernel timings, counts, floor and measured run (seconds per simulated second)."""
    from flexmech.models.kernels.layout import layout_of

    report, windows, compiled = counted_run(mech, until)
    steps, iterations = report["steps"], report["iterations"]
    evaluate = solve = factor = 0.0
    timings = {}
    for group in layout_of(mech.structure).groups:
        if group.signature not in timings:
            timings[group.signature] = time_kernels(group.signature)
        t = timings[group.signature]
        evaluate += group.n_elements * t["sweep"] + group.n_blocks * t["backward"]
        solve += group.n_blocks * t["substitute"]
        factor += group.n_elements * t["jacobian"] + group.n_blocks * t["factor"]
    floor = ((steps + iterations) * evaluate + iterations * solve + windows * factor) * 1e-6
    return {
        "timings": timings,
        "steps": steps,
        "iterations": iterations,
        "windows": windows,
        "floor": floor / until,
        "measured": report["seconds"] / until,
        "per_step": (evaluate, solve, factor),
        "until": until,
        "compiled": compiled,
        "report": report,
    }


def _print_row(title: str, row: dict, peer_name: str, peer: float, peer_accuracy: str, own_accuracy: str) -> None:
    print(f"\n{title}")
    for signature, t in row["timings"].items():
        kernels = ", ".join(f"{name} {t[name]:.3f}" for name in KERNELS)
        print(f"  kernels of {signature.key} (us per call, C -O2): {kernels}")
    evaluate, solve, factor = row["per_step"]
    steps = row["steps"]
    print(
        f"  one evaluation {evaluate:.1f} us, one solve {solve:.1f} us, one factorization {factor:.1f} us; "
        f"{steps} steps, {row['iterations'] / steps:.2f} iterations and {row['windows'] / steps:.3f} "
        f"factorizations per step"
    )
    target = peer / 2
    print(f"  {'':44s} {'s per simulated s':>18s}")
    print(
        f"  {'flexmech measured (warm, compiled)':44s} {row['measured']:18.4f}   {own_accuracy}; its kernels and "
        f"window compiled first in {row['compiled']:.1f} s (0: already there, the family's shared)"
    )
    print(f"  {'flexmech kernels alone (the floor)':44s} {row['floor']:18.4f}")
    print(f"  {peer_name:44s} {peer:18.4f}   {peer_accuracy}")
    print(f"  {'2x faster than the peer (issue 23 target)':44s} {target:18.4f}")
    print(
        f"  the floor is {row['floor'] / target:.2f}x the target and {row['floor'] / peer:.2f}x the peer; "
        f"the measured run {row['measured'] / row['floor']:.2f}x the floor"
    )
    # iterations k per step at which the floor meets the target, the factorizations as counted:
    # steps ((k + 1) E + k S) + windows F = target seconds
    budget = target * row["until"] * 1e6 - row["windows"] * factor
    needed = (budget / steps - evaluate) / (evaluate + solve)
    print(
        f"  to meet the target on these kernels, with nothing around them, a step may take "
        f"{needed:.2f} Newton iterations (it takes {row['iterations'] / steps:.2f})"
    )


def rod() -> None:
    from benchmarks.dynamics import ROD_UNTIL, document, period_and_drift
    from benchmarks.exudyn_peer import rod_free_vibration

    row = floor_row(document("rod_free_vibration.json"), ROD_UNTIL)
    r = row["report"]
    period, drift = period_and_drift(
        r["times"], r["outputs"]["bodies.tip.y"], r["energies"]["kinetic"], r["energies"]["potential"]
    )
    peer = rod_free_vibration(elements=10, step=1e-3, until=ROD_UNTIL, rho_inf=0.95)
    _print_row(
        f"Example I.1 as shipped (8 cubic elements, h = 1 ms, {ROD_UNTIL:g} s)",
        row,
        "Exudyn 10 linear, h = 1 ms",
        peer["wall_seconds"] / ROD_UNTIL,
        f"period {peer['period']:.6f} s, drift {peer['energy_drift']:.1e}",
        f"period {period:.6f} s, drift {drift:.1e}",
    )


def four_bar() -> None:
    from benchmarks.dynamics import BAR_UNTIL, document
    from benchmarks.exudyn_peer import four_bar as peer_four_bar

    row = floor_row(document("four_bar_dynamics.json"), BAR_UNTIL)
    r = row["report"]
    peer = peer_four_bar(elements=(8, 16, 16), step=2.5e-4, until=BAR_UNTIL, rho_inf=0.95)
    _print_row(
        f"Example II.2 as shipped (2/4/4 cubic elements, adaptive steps, {BAR_UNTIL:g} s)",
        row,
        "Exudyn 8/16/16 linear, h = 0.25 ms",
        peer["wall_seconds"] / BAR_UNTIL,
        f"balance {peer['balance_error']:.2e}, work {peer['input_work'][-1]:.3f} J",
        f"balance {r['energy_balance_error']:.2e}, work {r['energies']['input_work'][-1]:.3f} J",
    )


def fewer_rod_elements() -> None:
    """The rod with fewer cubic elements: its period error against a converged period (16
    cubic elements at h = 0.25 ms, as benchmarks.dynamics takes it)."""
    from benchmarks.dynamics import ROD_UNTIL, compile_kernels, document, flexmech_run, period_and_drift

    def run(n: int, **fields) -> tuple[float, float, float]:
        mech = document("rod_free_vibration.json", lambda d: d["elements"]["rod"].update(intervals=n))
        compile_kernels(mech)
        r, _ = flexmech_run(mech, until=ROD_UNTIL, **fields)
        period, drift = period_and_drift(
            r["times"], r["outputs"]["bodies.tip.y"], r["energies"]["kinetic"], r["energies"]["potential"]
        )
        return period, drift, r["seconds"] / ROD_UNTIL

    reference = run(16, every=4, step=0.00025)[0]
    print(f"\nExample I.1 with fewer cubic elements (period error against {reference:.6f} s)")
    print(f"  {'elements':>8s} {'period s':>10s} {'error':>9s} {'drift':>9s} {'s per simulated s':>18s}")
    for n in (1, 2, 4, 8):
        period, drift, per_second = run(n, every=5)
        print(f"  {n:8d} {period:10.6f} {abs(period / reference - 1):9.1e} {drift:9.1e} {per_second:18.4f}")


if __name__ == "__main__":
    os.environ.setdefault("FLEXMECH_CACHE_DIR", tempfile.mkdtemp(prefix="flexmech-floor-"))
    import exudyn

    print(f"exudyn {exudyn.__version__}; numpy {np.__version__}; flexmech cache {os.environ['FLEXMECH_CACHE_DIR']}")
    rod()
    four_bar()
    fewer_rod_elements()
