"""The compiled fast path: a whole Newton solve, or a whole continuation sweep, in one call.

Newton runs inside CasADi (rootfinder 'fast_newton', which can be code-generated); a sweep is
a mapaccum of it that carries each solution into the next point as its guess. The Functions
are generated to C, compiled with the system compiler and cached on disk by the mechanism's
structural hash (numbers are inputs, so one library serves every load, section and size).
Without a compiler the same Functions run on CasADi's virtual machine.

fast_newton has no line search: callers check the returned residual norm (the status), and
fall back to service.solvers.equilibrium for hard cases.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.caches.disk_cache import cache_dir
from flexmech.service.kernels.cache import compiler

_VERSION = "1"  # bump when the generated Functions change shape


@dataclass(frozen=True)
class FastOptions:
    tol_residual: float = 1e-12  # nondimensional |R|_inf
    max_iterations: int = 30


def compile_function(fn: ca.Function, key: str) -> tuple[ca.Function, bool]:
    """(compiled copy of fn, True), cached at <cache_dir>/libraries/<name>_<hash>.so (a section the
    cache's bound counts); (fn, False) when
    no compiler is available or compilation fails."""
    target = compiled_library(fn, key)
    if target is None:
        return fn, False
    return ca.external(fn.name(), str(target)), True


def compiled_library(fn: ca.Function, key: str) -> Path | None:
    """The shared library of fn generated to C and compiled (cached), or None."""
    cc = compiler()
    if cc is None:
        return None
    digest = hashlib.sha256(f"{key}|{ca.__version__}|{_VERSION}|{cc}".encode()).hexdigest()[:16]
    target = cache_dir() / "libraries" / f"{fn.name()}_{digest}.so"
    if not target.exists():
        target.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory() as tmp:
            generator = ca.CodeGenerator(f"{fn.name()}.c", {"with_header": False})
            generator.add(fn)
            source = generator.generate(tmp + os.sep)
            partial = Path(tmp) / "lib.so"
            done = subprocess.run(
                [cc, "-O2", "-fPIC", "-shared", source, "-o", str(partial), "-lm"], capture_output=True, text=True
            )
            if done.returncode != 0:
                return None
            # rename is atomic: concurrent processes never load a half-written library
            staged = target.with_suffix(f".{os.getpid()}.tmp")
            shutil.copyfile(partial, staged)
            os.replace(staged, target)
    return target


class FastPath:
    """Compiled equilibrium solves of one mechanism structure.

    solve(p, z0) -> (z, |R|_inf); sweep(P, z0) -> (Z, norms, Y) for the columns of P with
    continuation, where Y holds `outputs` (names of mech.graphs.output_names; default: all)
    at each point, nondimensional, in the order given. Computing only the outputs a caller
    needs matters: all of them cost about as much as the Newton iterations.
    Not thread-safe: give each thread its own FastPath.
    """

    def __init__(
        self,
        mech: Mechanism,
        options: FastOptions = FastOptions(),
        compile: bool = True,
        outputs: tuple[str, ...] | None = None,
    ):
        self.mechanism = mech
        self.options = options
        self.compile = compile
        g = mech.graphs
        names = g.output_names
        self.output_names = tuple(names) if outputs is None else tuple(outputs)
        unknown = [n for n in self.output_names if n not in names]
        if unknown:
            raise MechanismError("outputs", f"unknown output(s) {', '.join(unknown)}")
        selected = [names.index(n) for n in self.output_names]
        rootfinder = ca.rootfinder(
            "equilibrium_newton",
            "fast_newton",
            g.residual,
            {
                "abstol": options.tol_residual,
                "abstolStep": 1e-14,
                "max_iter": options.max_iterations,
                "error_on_fail": False,
            },
        )
        z0 = ca.MX.sym("z0", mech.n_free)
        p = ca.MX.sym("p", len(mech.parameters))
        z = rootfinder(z0, p)
        norm = ca.mmax(ca.fabs(g.residual(z, p))) if mech.n_free else ca.MX(0)
        # Inline the outputs on SX symbols and keep only the selected entries, so the
        # generated code computes nothing else (indexing an MX call would evaluate them all).
        z_sx, p_sx = ca.SX.sym("z", mech.n_free), ca.SX.sym("p", len(mech.parameters))
        chosen = ca.Function("chosen_outputs", [z_sx, p_sx], [g.outputs(z_sx, p_sx)[selected]], ["z", "p"], ["y"])
        y = chosen(z, p)
        self._step = ca.Function("fast_step", [z0, p], [z, norm, y], ["z0", "p"], ["z", "residual_norm", "y"])
        self._key = f"{mech.structure.key}|{options}|{','.join(self.output_names)}"
        self.solve_function, self.compiled = self._build(
            ca.Function("fast_solve", [z0, p], [z, norm], ["z0", "p"], ["z", "residual_norm"])
        )
        self._sweeps: dict[int, ca.Function] = {}
        self._solve_buffer: _Bound | None = None
        self._sweep_buffers: dict[int, _Bound] = {}

    def _build(self, fn: ca.Function) -> tuple[ca.Function, bool]:
        if not self.compile:
            return fn, False
        return compile_function(fn, f"{self._key}|{fn.name()}")

    def solve(self, p: np.ndarray | None = None, z0: np.ndarray | None = None) -> tuple[np.ndarray, float]:
        p = self.mechanism.p() if p is None else p
        if self._solve_buffer is None:
            self._solve_buffer = _Bound(
                self.solve_function, [(self.mechanism.n_free,), (len(p),)], [(self.mechanism.n_free,), (1,)]
            )
        b = self._solve_buffer
        b.inputs[0][:] = 0.0 if z0 is None else z0
        b.inputs[1][:] = p
        b.trigger()
        return b.outputs[0].copy(), float(b.outputs[1][0])

    def sweep_function(self, points: int) -> ca.Function:
        if points not in self._sweeps:
            fn = self._step.mapaccum(f"fast_sweep_{points}", points)
            self._sweeps[points] = self._build(fn)[0]
        return self._sweeps[points]

    def sweep(self, P: np.ndarray, z0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """P: (n_params, points) nondimensional parameters per point.
        Returns Z (n_free, points), residual norms (points,), Y (n_outputs, points)."""
        n, points = self.mechanism.n_free, P.shape[1]
        ny = len(self.output_names)
        bound = self._sweep_buffers.get(points)
        if bound is None:
            # CasADi matrices are column-major: a (points, rows) C-array is a (rows, points) matrix
            bound = _Bound(
                self.sweep_function(points), [(n,), (points, P.shape[0])], [(points, n), (points,), (points, ny)]
            )
            self._sweep_buffers[points] = bound
        bound.inputs[0][:] = 0.0 if z0 is None else z0
        bound.inputs[1][:] = P.T
        bound.trigger()
        return bound.outputs[0].T.copy(), bound.outputs[1].copy(), bound.outputs[2].T.copy()

    def path_parameters(self, path: str, values_doc: np.ndarray) -> np.ndarray:
        """Parameter matrix for a sweep of one numeric field over values (document units)."""
        m = self.mechanism
        k = m.parameter_index(path)
        P = np.tile(m.p()[:, None], (1, len(values_doc)))
        P[k, :] = np.asarray(values_doc) * m.nd_per_doc(m.parameters[k].kind)
        return P


class _Bound:
    """A Function evaluated in place on numpy arrays (CasADi's buffer API): no conversion of
    inputs or outputs, which otherwise costs more than the compiled solve itself."""

    def __init__(self, fn: ca.Function, input_shapes, output_shapes):
        self.inputs = [np.zeros(s) for s in input_shapes]
        self.outputs = [np.zeros(s) for s in output_shapes]
        self._buffer, self.trigger = fn.buffer()
        for i, a in enumerate(self.inputs):
            self._buffer.set_arg(i, memoryview(a))
        for i, a in enumerate(self.outputs):
            self._buffer.set_res(i, memoryview(a))
