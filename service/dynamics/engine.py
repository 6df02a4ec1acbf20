"""The kernel time stepping of one structure, scheme and set of moving parameters: the Functions
a run calls (windows of steps, the consistent start, a rescue step by full Newton) and the
elements' data, built in milliseconds from the chain signatures' chunks (compiled ones where
the kernel cache has them, service.kernels; interpreted otherwise).

Python calls one Function per window of steps; a window factors the Newton system at its first
step (service.dynamics.kernel_window)."""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from functools import cached_property

import casadi as ca
import numpy as np

from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.structure import Structure
from flexmech.models.kernels.link_data import link_data
from flexmech.service.dynamics.full_newton import newton
from flexmech.service.dynamics.kernel_groups import padded
from flexmech.service.dynamics.kernel_records import Factors
from flexmech.service.dynamics.kernel_system import NEWTON_TOLERANCE, StepSystem
from flexmech.service.dynamics.kernel_window import Stepper
from flexmech.service.dynamics.schemes import Scheme, StageScheme
from flexmech.service.dynamics.stage_window import StageStepper

WINDOW_ACCEPTANCE = 10 * NEWTON_TOLERANCE  # a window's step whose residual is below this counts
RESCUE_ITERATIONS = 16  # full Newton, for a step that the window's factors do not settle
ENGINES = 8  # kept in memory per process
RECHECK = 2.0  # seconds between looks for a window's library while it runs interpreted


@dataclass
class Engine:
    structure: Structure
    scheme: Scheme | StageScheme
    moving: tuple[int, ...]
    compiled: dict = field(default_factory=dict)  # ChainSignature -> compiled Chunks

    def __post_init__(self):
        self.system = StepSystem(self.structure, self.moving, compiled=self.compiled)
        self.stepper = stepper_of(self.system, self.scheme)
        self._windows: dict[int, tuple[ca.Function, bool]] = {}  # steps -> (window, compiled as a whole)
        self._glue: dict[int, ca.Function] = {}  # steps -> the window on its kernels, glue interpreted
        self._keys: dict[int, str] = {}
        self._looked: dict[int, float] = {}

    @property
    def n_x(self) -> int:
        return self.system.layout.n_x

    @property
    def n_lam(self) -> int:
        return self.system.layout.n_lam

    # ---- data -------------------------------------------------------------------------------------
    @cached_property
    def _data_function(self) -> ca.Function:
        ctx = AssemblyContext(self.structure)
        columns = []
        for g in self.system.layout.groups:
            block = ca.horzcat(*[link_data(ctx, c.topology, g.signature) for c in g.chains])
            columns.append(ca.horzcat(block, ca.SX.zeros(block.shape[0], padded(block.shape[1]) - block.shape[1])))
        return ca.Function("element_data", [ctx.p], columns)

    def data(self, p: np.ndarray) -> list[np.ndarray]:
        """Per chain group, every element's data (padded to whole chunks) at parameters p."""
        if not self.system.layout.groups:  # no link: a Function of no outputs answers None
            return []
        out = self._data_function(p)
        out = out if isinstance(out, (list, tuple)) else [out]
        return [np.asarray(q, dtype=float) for q in out]

    def kernels(self) -> str:
        """How its windows ran: "compiled" (kernels and windows), "kernels compiled" (their glue
        interpreted) or "interpreted"."""
        signatures = [g.signature for g in self.system.layout.groups]
        if not signatures or any(s not in self.compiled for s in signatures):
            return "interpreted"
        windows = [compiled for _, compiled in self._windows.values()]
        return "compiled" if windows and all(windows) else "kernels compiled"

    # ---- Functions ----------------------------------------------------------------------------------
    def window(self, steps: int) -> ca.Function:
        """The window of `steps` (see glue_window), compiled as a whole once the build queue has
        made it (looked for at most every RECHECK seconds while it runs interpreted)."""
        fn, compiled = self._windows.get(steps, (None, False))
        if fn is None or (not compiled and time.monotonic() - self._looked.get(steps, 0.0) > RECHECK):
            self._looked[steps] = time.monotonic()
            native = self._compiled_glue(steps)
            fn, compiled = (native, True) if native is not None else (self.glue_window(steps), False)
            self._windows[steps] = (fn, compiled)
        return fn

    def _compiled_glue(self, steps: int) -> ca.Function | None:
        """The compiled window, when every kernel it calls is compiled and so is it
        (service.kernels.windows); None otherwise."""
        signatures = [g.signature for g in self.system.layout.groups]
        if not signatures or any(s not in self.compiled for s in signatures):
            return None
        from flexmech.service.kernels.windows import compiled_window, window_key

        glue = self.glue_window(steps)
        if steps not in self._keys:
            self._keys[steps] = window_key(glue)
        return compiled_window(glue, self._keys[steps], signatures)

    def glue_window(self, steps: int) -> ca.Function:
        """(s0, h, P, PDOT, PDDOT, damping, mask, count, data...) -> (S, MONITOR, NORMS,
        ITERATIONS): up to `steps` steps, a column each, of which the first `count` run; a step
        after one that did not settle computes nothing (its norm is infinite). One Function per
        window length serves every count: the adaptive steps' last windows build nothing new."""
        if steps not in self._glue:
            st = self.stepper
            state, h, p, pdot, pddot, damping, mask, data = st._symbols()
            S = stages_of(self.scheme)
            P, PD, PDD = (
                ca.MX.sym(name, q.numel(), steps * S) for name, q in (("P", p), ("PDOT", pdot), ("PDDOT", pddot))
            )

            def columns_of(j):  # step j's columns: its end, or its stages
                return (P[:, j], PD[:, j], PDD[:, j]) if S == 1 else (q[:, j * S : (j + 1) * S] for q in (P, PD, PDD))

            count = ca.MX.sym("count")
            first = st.first_step_function(state, h, *columns_of(0), damping, mask, *data)
            s, monitor, norm, used = first[:4]
            factors = first[4:]
            columns = [[s], [monitor], [norm], [used]]
            for j in range(1, steps):
                alive = (norm <= WINDOW_ACCEPTANCE) * (count > j)
                s, monitor, norm, used = st.step_function(*factors, alive, s, h, *columns_of(j), damping, mask, *data)
                for column, value in zip(columns, (s, monitor, norm, used)):
                    column.append(value)
            window = ca.Function(
                f"kernel_window_{steps}",
                [state, h, P, PD, PDD, damping, mask, count, *data],
                [ca.horzcat(*column) for column in columns],
                ["s0", "h", "P", "PDOT", "PDDOT", "damping", "mask", "count", *[f"data{i}" for i in range(len(data))]],
                ["S", "MONITOR", "NORMS", "ITERATIONS"],
            )
            self._glue[steps] = window
        return self._glue[steps]

    @cached_property
    def rescue(self) -> ca.Function:
        """(s0, h, p, pdot, pddot, damping, mask, data...) -> (state, monitor, norm): one step by
        Newton, its factors made at every iteration (a step the window's factors do not settle).
        A stage scheme's: each stage by full Newton (p, pdot, pddot per stage)."""
        st, sys = self.stepper, self.system
        if isinstance(st, StageStepper):
            state, h, P, PD, PDD, damping, mask, data = st._step_symbols()
            out = st.rescue_step(state, h, P, PD, PDD, damping, mask, data, RESCUE_ITERATIONS)
            return ca.Function("stage_rescue", [state, h, P, PD, PDD, damping, mask, *data], list(out))
        state, h, p, pdot, pddot, damping, mask, data = st._symbols()
        fa, k = st.coefficients(h)
        affine, c_a1 = st._affine(state, h)
        _, _, _, qdd, lam = st.state.split(state)
        si = sys.step_inputs(affine, k, p, pdot, pddot, damping, mask, data)
        Z, _, ev = newton(sys, ca.vertcat(qdd, lam), si, RESCUE_ITERATIONS)
        u = Z[: self.n_x]
        cX, cV, _ = affine
        new_state = ca.vertcat(cX + k[0] * u, cV + k[1] * u, c_a1 + fa * u, u, Z[self.n_x :])
        return ca.Function(
            "kernel_rescue", [state, h, p, pdot, pddot, damping, mask, *data], [new_state, st.monitor(ev, si), ev.norm]
        )

    @cached_property
    def static_iteration(self) -> ca.Function:
        """(x, Z, p, mask, data...) -> (Z - dZ, norm at Z): one full Newton iteration of the
        static equilibrium near x: the step system with inertia and damping off (k = (1, 0, 0,
        1): the coordinates are x + u, nothing moves), its factors made at Z = [u; lam]."""
        sys, st = self.system, self.stepper
        _, _, p, pdot, pddot, damping, mask, data = st._symbols()
        x, Z = ca.MX.sym("x", self.n_x), ca.MX.sym("Z", sys.n_z)
        k = ca.MX(ca.DM([1, 0, 0, 1]))
        still = ca.MX.zeros(self.n_x)
        si = sys.step_inputs(
            (x, still, still), k, p, ca.MX.zeros(pdot.shape), ca.MX.zeros(pddot.shape), ca.MX(0), mask, data
        )
        one = ca.MX(1)
        factors = sys.factorize(Z, si)
        ev = sys.evaluate(Z, one, si, factors.kept_reverse)
        return ca.Function(
            "kernel_static_iteration", [x, Z, p, mask, *data], [Z - sys.solve(ev, one, factors), ev.norm]
        )

    @cached_property
    def start(self) -> ca.Function:
        """(x, v, p, pdot, pddot, damping, mask, data...) -> (qdd, lam, norm, monitor): the
        accelerations and multipliers consistent with (x, v): the equations with the
        constraints' second derivatives, linear in them (one exact Newton step, and one more for
        round-off), and the monitor there."""
        system = StepSystem(self.structure, self.moving, level="acceleration", compiled=self.compiled)
        st = Stepper(system, self.scheme)
        _, _, p, pdot, pddot, damping, mask, data = st._symbols()
        x, v = ca.MX.sym("x", self.n_x), ca.MX.sym("v", self.n_x)
        k = ca.MX(ca.DM([0, 0, 1, 1]))
        si = system.step_inputs((x, v, ca.MX.zeros(self.n_x)), k, p, pdot, pddot, damping, mask, data)
        Z, one = ca.MX.zeros(system.n_z), ca.MX(1)
        factors = system.factorize(Z, si)
        for _ in range(2):
            ev = system.evaluate(Z, one, si, factors.kept_reverse)
            Z = Z - system.solve(ev, one, factors)
        ev = system.evaluate(Z, one, si, factors.kept_reverse)
        return ca.Function(
            "kernel_start",
            [x, v, p, pdot, pddot, damping, mask, *data],
            [Z[: self.n_x], Z[self.n_x :], ev.norm, st.monitor(ev, si)],
        )


def stepper_of(system: StepSystem, scheme: Scheme | StageScheme) -> Stepper:
    return StageStepper(system, scheme) if isinstance(scheme, StageScheme) else Stepper(system, scheme)


def stages_of(scheme: Scheme | StageScheme) -> int:
    """The columns of loads and motions a step takes: one (its end), or one per stage."""
    return scheme.stages if isinstance(scheme, StageScheme) else 1


_engines: OrderedDict[tuple, Engine] = OrderedDict()
_lock = threading.Lock()


def engine_for(structure: Structure, scheme: Scheme, moving: tuple[int, ...], compiled: dict | None = None) -> Engine:
    """The engine of a structure, scheme and moving parameters, kept (a few) per process; a new
    one when compiled kernels have arrived since."""
    compiled = compiled or {}
    key = (structure, scheme, moving, tuple(sorted(str(s) for s in compiled)))
    with _lock:
        engine = _engines.get(key)
        if engine is None:
            engine = Engine(structure, scheme, moving, compiled)
            _engines[key] = engine
            while len(_engines) > ENGINES:
                _engines.popitem(last=False)
        _engines.move_to_end(key)
        return engine


__all__ = ["Engine", "Factors", "engine_for"]
