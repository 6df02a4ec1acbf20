"""The time step on the kernel system (service.dynamics.kernel_system), as Functions that a
window of steps (service.dynamics.engine) chains.

The window factors the Newton system once, at its first step's predictor, and every step of
the window iterates on those factors (modified Newton): the residual is exact at every
iteration, so the factors' age changes the rate of convergence only. Each iteration is
accelerated by Anderson's mixing with the one before (a secant step): it recovers much of
what old factors lose on the stiff shear and axial modes, whose accelerations change sign
from step to step. Iterations run while the residual is above the tolerance, up to
MAX_ITERATIONS: once it is below, the remaining iterations are skipped as a whole (a Switch,
Stepper.gated_iteration); kernels that run interpreted (no compiled library yet) run each
iteration as one expanded Function. A step left above the tolerance is reported by its
residual: the caller cuts the window there and starts the next one, with fresh factors, from
the last good step.

The state carried from step to step is [x; v; a; qdd; lam] (the energy form's coordinates,
rates, the scheme's acceleration-like variable, accelerations, multipliers). Per step the
window also returns the monitor (kinetic energy, the potential without the varying loads, the
input power, the damping power, the contacts' friction and damping powers, the prescribed
motions' forces), the residual's norm and the iterations it took.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import casadi as ca

from flexmech.service.dynamics.kernel_groups import padded
from flexmech.service.dynamics.kernel_records import Evaluation, Factors, StepInputs
from flexmech.service.dynamics.kernel_system import NEWTON_TOLERANCE, StepSystem
from flexmech.service.dynamics.schemes import Scheme

MAX_ITERATIONS = 8


@dataclass(frozen=True)
class StateLayout:
    n_x: int
    n_lam: int

    @property
    def size(self) -> int:
        return 4 * self.n_x + self.n_lam

    def split(self, s):
        n = self.n_x
        return s[:n], s[n : 2 * n], s[2 * n : 3 * n], s[3 * n : 4 * n], s[4 * n :]


class Stepper:
    """The Functions of the kernel time stepping of one structure, scheme and set of moving
    parameters: one step on given factors, and a window's first step (which makes them); the
    engine (service.dynamics.engine) chains them into windows."""

    def __init__(self, system: StepSystem, scheme: Scheme):
        self.system, self.scheme = system, scheme
        L = system.layout
        self.state = StateLayout(L.n_x, L.n_lam)
        self.n_p = len(system.structure.parameters)
        self.n_moving = len(system.moving)
        self.n_groups = len(L.groups)
        self.expanded = system.interpreted  # see gated_iteration

    def data_shapes(self) -> list[tuple[int, int]]:
        """Per chain group: the shape of its element data (padded to whole chunks)."""
        return [(g.signature.n_data, padded(g.n_elements)) for g in self.system.layout.groups]

    # ---- symbols ----------------------------------------------------------------------------------
    def _symbols(self):
        data = [ca.MX.sym(f"data{i}", *shape) for i, shape in enumerate(self.data_shapes())]
        return (
            ca.MX.sym("state", self.state.size),
            ca.MX.sym("h"),
            ca.MX.sym("p", self.n_p),
            ca.MX.sym("pdot", self.n_moving),
            ca.MX.sym("pddot", self.n_moving),
            ca.MX.sym("damping"),
            ca.MX.sym("mask", self.n_p),
            data,
        )

    def _step_symbols(self):
        """The step Functions' inputs: _symbols(), with the loads and motions at the step's end (a
        stage scheme's: at its stages, stage_window.StageStepper)."""
        return self._symbols()

    def _iteration_symbols(self):
        """(factors, a step's symbols, the step's shared inputs from them), made in this order."""
        f = self._factor_symbols()
        state, h, p, pdot, pddot, damping, mask, data = self._symbols()
        _, k = self.coefficients(h)
        affine, _ = self._affine(state, h)
        return (
            f,
            (state, h, p, pdot, pddot, damping, mask, data),
            self.system.step_inputs(affine, k, p, pdot, pddot, damping, mask, data),
        )

    def _factor_symbols(self) -> Factors:
        sys = self.system
        shapes = [(ch.factor_size, gr.blocks) for ch, gr in zip(sys.chunks, sys.groups)]
        return Factors(
            [ca.MX.sym(f"kept_rev{i}", *b) for i, b in enumerate(shapes)],
            [ca.MX.sym(f"kept_fwd{i}", *b) for i, b in enumerate(shapes)],
            ca.MX.sym("inverse", sys.layout.n_global, sys.layout.n_global),
        )

    def coefficients(self, h):
        """(d a / d u, k = (kx, kv, ka, k_rho)) of the scheme for the step h."""
        s = self.scheme
        fa = (1 - s.alpha_f) / (1 - s.alpha_m)
        kx, kv = h**2 * s.beta * fa, h * s.gamma * fa
        return fa, ca.vertcat(kx, kv, 1, kx)

    def _affine(self, state, h):
        sc = self.scheme
        x, v, a, qdd, _ = self.state.split(state)
        c_a1 = (sc.alpha_f * qdd - sc.alpha_m * a) / (1 - sc.alpha_m)
        cX = x + h * v + h**2 * ((0.5 - sc.beta) * a + sc.beta * c_a1)
        cV = v + h * ((1 - sc.gamma) * a + sc.gamma * c_a1)
        return (cX, cV, ca.MX.zeros(self.state.n_x)), c_a1

    # ---- the Functions ----------------------------------------------------------------------------
    @cached_property
    def step_function(self) -> ca.Function:
        """(factors..., alive, state, h, p, pdot, pddot, damping, mask, data...) -> (state,
        monitor, norm, iterations): one step on given factors; alive = 0 (a step before it in
        the window did not settle) computes nothing and reports an infinite norm."""
        f = self._factor_symbols()
        state, h, p, pdot, pddot, damping, mask, data = self._step_symbols()
        inputs = [*f.parts(), state, h, p, pdot, pddot, damping, mask, *data]
        new_state, monitor, norm, used, _ = self._step(f, state, h, p, pdot, pddot, damping, mask, data)
        live = ca.Function("kernel_step_live", inputs, [new_state, monitor, norm, used])
        # a dead step is a branch: inlined, its gated kernels would still cost the VM most of a step
        dead = ca.Function("kernel_step_dead", inputs, [state, ca.MX.zeros(monitor.shape), ca.MX(ca.inf), ca.MX(0)])
        branch = ca.Function.if_else("kernel_step_branch", live, dead)
        alive = ca.MX.sym("alive")
        return ca.Function("kernel_step", [*f.parts(), alive, *inputs[len(f.parts()) :]], branch(alive, *inputs))

    @cached_property
    def first_step_function(self) -> ca.Function:
        """(state, h, p, pdot, pddot, damping, mask, data...) -> (state, monitor, norm,
        iterations, factors...): a step that makes the factors at its predictor."""
        state, h, p, pdot, pddot, damping, mask, data = self._step_symbols()
        out = self._step(None, state, h, p, pdot, pddot, damping, mask, data)
        return ca.Function(
            "kernel_first_step", [state, h, p, pdot, pddot, damping, mask, *data], [*out[:4], *out[4].parts()]
        )

    def _step(self, factors: Factors | None, state, h, p, pdot, pddot, damping, mask, data):
        sys = self.system
        fa, k = self.coefficients(h)
        affine, c_a1 = self._affine(state, h)
        _, _, _, qdd, lam = self.state.split(state)
        si = sys.step_inputs(affine, k, p, pdot, pddot, damping, mask, data)
        Z = ca.vertcat(qdd, lam)  # the predictor: the last accelerations and multipliers
        if factors is None:
            factors = sys.factorize(Z, si)
        if self.expanded:
            ev = Evaluation.of(
                self.evaluation_function(*factors.kept_reverse, state, h, p, pdot, pddot, damping, mask, *data, Z),
                self.n_groups,
            )
        else:
            ev = sys.evaluate(Z, ca.MX(1), si, factors.kept_reverse)
        carry = [Z, ca.MX.zeros(sys.n_z), ca.MX.zeros(sys.n_z), ca.MX(0), ca.MX(0), *ev.parts()]
        iterate = self.gated_iteration
        for _ in range(MAX_ITERATIONS):  # one Function called again and again: its code is generated once
            carry = iterate(*factors.parts(), *si.parts(), *carry)
        Z, used, ev = carry[0], carry[4], Evaluation.of(carry[5:], self.n_groups)
        n_x = self.state.n_x
        u = Z[:n_x]
        cX, cV, _ = affine
        new_state = ca.vertcat(cX + k[0] * u, cV + k[1] * u, c_a1 + fa * u, u, Z[n_x:])
        return new_state, self.monitor(ev, si), ev.norm, used, factors

    @cached_property
    def iteration_function(self) -> ca.Function:
        """(factors..., the step's inputs..., Z, previous, g_previous, have, used,
        evaluation...) -> (the same carry, one iteration on): the chord step on the window's
        factors, accelerated by Anderson's mixing with the iteration before
        (a secant step). It computes unconditionally: gated_iteration runs it only while the
        carried residual is above the tolerance. The step's inputs come made (the predictor's
        affine parts gathered per element), once per step instead of once per iteration."""
        sys = self.system
        f, _, made = self._iteration_symbols()
        si = made.symbols()
        Z, previous, g_previous = (ca.MX.sym(name, sys.n_z) for name in ("Z", "previous", "g_previous"))
        have, used = ca.MX.sym("have"), ca.MX.sym("used")
        one = ca.MX(1)
        shapes = [part.shape for part in sys.evaluate(Z, one, si, f.kept_reverse).parts()]
        parts = [ca.MX.sym(f"evaluation{i}", *shape) for i, shape in enumerate(shapes)]
        ev = Evaluation.of(parts, self.n_groups)
        g = -sys.solve(ev, one, f)  # the chord step
        dZ, dg = Z - previous, g - g_previous
        gamma = have * ca.dot(dg, g) / (ca.dot(dg, dg) + 1e-300)
        Z_next = Z + g - gamma * (dZ + dg)
        ev_next = sys.evaluate(Z_next, one, si, f.kept_reverse)
        return ca.Function(
            "kernel_iteration",
            [*f.parts(), *si.parts(), Z, previous, g_previous, have, used, *parts],
            [Z_next, Z, g, one, used + 1, *ev_next.parts()],
        )

    @cached_property
    def gated_iteration(self) -> ca.Function:
        """iteration_function gated as a whole: a Switch between it and a pass-through of the
        carry, on the carried norm being above the tolerance, so that a converged step's
        remaining iterations cost a branch and a copy of the carry (gating each kernel item
        instead cost the rod's warm step 146 us against 129, measured back to back).
        Kernels that run interpreted (no compiled library yet) have the iteration expanded into
        one SX Function: CasADi's SX machine then runs the step's arithmetic without the MX
        machine's calls and copies, and the padding items (constant flags) drop out; 1.7x faster
        on the rod and the four-bar (interpreted rows); 64 elements build in 1 s instead of 0.6
        and hold 50 MB more. Compiled kernels cannot be expanded, nor need to be."""
        fn = self.iteration_function
        n_carry = fn.n_out()  # the carry is the last n_carry inputs, the norm last of all
        symbols = [ca.SX.sym(fn.name_in(i), fn.sparsity_in(i)) for i in range(fn.n_in())]
        idle = ca.Function("kernel_iteration_idle", symbols, symbols[-n_carry:])
        switch = ca.Function.if_else("kernel_iteration_switch", fn.expand() if self.expanded else fn, idle)
        inputs = [ca.MX.sym(fn.name_in(i), fn.sparsity_in(i)) for i in range(fn.n_in())]
        return ca.Function("kernel_iteration_gated", inputs, switch(inputs[-1] > NEWTON_TOLERANCE, *inputs))

    @cached_property
    def evaluation_function(self) -> ca.Function:
        """(kept_rev..., state, h, p, pdot, pddot, damping, mask, data..., Z) -> the
        evaluation's parts: a step's first evaluation, expanded like gated_iteration."""
        f, (state, h, p, pdot, pddot, damping, mask, data), si = self._iteration_symbols()
        Z = ca.MX.sym("Z", self.system.n_z)
        ev = self.system.evaluate(Z, ca.MX(1), si, f.kept_reverse)
        return ca.Function(
            "kernel_evaluation", [*f.kept_reverse, state, h, p, pdot, pddot, damping, mask, *data, Z], ev.parts()
        ).expand()

    def monitor(self, ev: Evaluation, si: StepInputs) -> ca.MX:
        """(kinetic, held potential, input power, damping power, the contacts' friction power and
        damping power, motion forces...)."""
        sys = self.system
        kinetic = ev.global_energies[0] + ev.energies[0]
        held, power = ev.global_energies[2] + ev.energies[1], ev.global_energies[3]
        if sys.gravity is not None:  # the links' weight: -g . first moment; its power, g . momentum
            g, varying = si.p[sys.gravity], si.mask[sys.gravity]
            held = held - ca.dot((1 - varying) * g, ev.energies[2:4])
            power = power + ca.dot(varying * g, ev.energies[4:6])
        Q = []
        for row, body in self._motion_rows:
            value = ev.all_rows[row]
            for r, start in enumerate(sys.routed_bodies):
                if body is not None and start == body:
                    value = value + ev.routed[r]
            Q.append(value)
        Q = ca.vertcat(*Q) if Q else ca.MX(0, 1)
        if self.n_moving:
            power = power + ca.dot(Q, si.pdot)
        return ca.vertcat(
            kinetic, held, power, 2 * si.damping * kinetic, ev.global_energies[4], ev.global_energies[5], Q
        )

    @cached_property
    def _motion_rows(self) -> list[tuple[int, int | None]]:
        """Per moving parameter: its coordinate's row among all rows, and its body when the
        coordinate is an angle (the clamped starts on that body add their theta_0 rows)."""
        s, out = self.system.structure, []
        for index in self.system.moving:
            pointer = s.parameters[index].pointer
            b, c = next((b, c) for b, row in enumerate(s.prescribed) for c in range(3) if row[c] == pointer)
            out.append((3 * b + c, b if c == 2 else None))
        return out
