"""The time step of a stage scheme (service.dynamics.schemes.StageScheme, SDIRK) on the kernel
system, as Functions of the same shapes as the generalized-alpha step's (kernel_window.Stepper)
but for the loads and motions, which come per stage: P, PDOT, PDDOT of a step are (n, stages)
columns at t_n + c_i h.

Each stage is the generalized-alpha step's Newton problem with its own affine parts (the
positions and velocities that the stages before it give) and the same coefficients
k = (h^2 gamma^2, h gamma, 1, h^2 gamma^2): the window's factors, made at its first stage,
serve every stage of every step (modified Newton, accelerated as in kernel_window). A stage's
first guess is the line through the two known nodes nearest its own (the step's start and the
stages before it; predictor()).

The state has the generalized-alpha one's layout, [x; v; e; qdd; lam], qdd the last stage's
accelerations and e, in place of generalized-alpha's acceleration-like variable, the step's
local error estimate: its positions less the embedded third-order solution's, filtered on the
stiff modes (_filtered; the adaptive steps follow it, service.dynamics.adaptive). The monitor's
energies and the motions' forces are the step's end (the last stage); its powers are the
stages' powers weighted by the scheme's b, the mean power over the step, so that h times them
is the step's work to the scheme's order (the runner sums them so:
service.dynamics.stepping.work_increments)."""

from __future__ import annotations

from functools import cached_property

import casadi as ca

from flexmech.service.dynamics.full_newton import newton
from flexmech.service.dynamics.kernel_records import Evaluation, Factors
from flexmech.service.dynamics.kernel_window import MAX_ITERATIONS, Stepper
from flexmech.service.dynamics.schemes import StageScheme

POWERS = slice(2, 6)  # the monitor's rows of powers (inputs, damping, contacts' friction and damping)


class StageStepper(Stepper):
    scheme: StageScheme

    @property
    def stages(self) -> int:
        return self.scheme.stages

    def coefficients(self, h):
        g = self.scheme.gamma
        kx = (h * g) ** 2
        return None, ca.vertcat(kx, h * g, 1, kx)

    def _affine(self, state, h):
        """The first stage's affine parts (their shapes serve the iteration's symbols)."""
        x, v, _, _, _ = self.state.split(state)
        g = self.scheme.gamma
        return (x + h * g * v, v, ca.MX.zeros(self.state.n_x)), None

    def _step_symbols(self):
        """_symbols() with the loads and motions as (n, stages) columns: the step Functions
        (step_function, first_step_function) take them so."""
        state, h, p, pdot, pddot, damping, mask, data = self._symbols()
        S = self.stages
        P, PD, PDD = (ca.MX.sym(name, q.numel(), S) for name, q in (("P", p), ("PD", pdot), ("PDD", pddot)))
        return state, h, P, PD, PDD, damping, mask, data

    @cached_property
    def stage_evaluation(self) -> ca.Function:
        """(kept_rev..., the stage's inputs..., Z) -> the evaluation's parts: a stage's first
        evaluation (expanded when the kernels run interpreted, as kernel_window's)."""
        f, _, made = self._iteration_symbols()
        si = made.symbols()
        Z = ca.MX.sym("Z", self.system.n_z)
        ev = self.system.evaluate(Z, ca.MX(1), si, f.kept_reverse)
        fn = ca.Function("stage_evaluation", [*f.kept_reverse, *si.parts(), Z], ev.parts())
        return fn.expand() if self.expanded else fn

    def rescue_step(self, state, h, P, PD, PDD, damping, mask, data, iterations: int):
        """(state, monitor, norm): the step by full Newton on every stage, its factors made again
        at every iteration (a step the window's factors do not settle: the four-bar's coupler
        buckling, where modified Newton stalls near a residual of 1e-9); the error filter on
        the last stage's factors."""
        return self._step(None, state, h, P, PD, PDD, damping, mask, data, full_newton=iterations)[:3]

    def _step(self, factors: Factors | None, state, h, P, PD, PDD, damping, mask, data, full_newton: int = 0):
        sys, sc = self.system, self.scheme
        _, k = self.coefficients(h)
        x, v, _, qdd, lam = self.state.split(state)
        Z = ca.vertcat(qdd, lam)  # the first stage's predictor: the last accelerations and multipliers
        n_x = self.state.n_x
        stage_accelerations, stage_unknowns, power, norm, used_all = [], [], 0, ca.MX(0), ca.MX(0)
        for i in range(self.stages):
            cX = x + sc.nodes[i] * h * v
            cV = v
            for j, A_j in enumerate(stage_accelerations):
                cX = cX + (h**2 * sc.squared[i][j]) * A_j
                cV = cV + (h * sc.a[i][j]) * A_j
            si = sys.step_inputs((cX, cV, ca.MX.zeros(n_x)), k, P[:, i], PD[:, i], PDD[:, i], damping, mask, data)
            known = [ca.vertcat(qdd, lam)] + stage_unknowns
            Z = sum(w * known[j] for j, w in predictor(sc.nodes, i))
            if full_newton:
                Z, factors, ev = newton(sys, Z, si, full_newton)
                used = ca.MX(full_newton)
            else:
                if factors is None:
                    factors = sys.factorize(Z, si)
                ev = Evaluation.of(self.stage_evaluation(*factors.kept_reverse, *si.parts(), Z), self.n_groups)
                carry = [Z, ca.MX.zeros(sys.n_z), ca.MX.zeros(sys.n_z), ca.MX(0), ca.MX(0), *ev.parts()]
                for _ in range(MAX_ITERATIONS):
                    carry = self.gated_iteration(*factors.parts(), *si.parts(), *carry)
                Z, used, ev = carry[0], carry[4], Evaluation.of(carry[5:], self.n_groups)
            stage_accelerations.append(Z[:n_x])
            stage_unknowns.append(Z)
            monitor = self.monitor(ev, si)
            power = power + sc.weights[i] * monitor[POWERS]
            norm, used_all = ca.fmax(norm, ev.norm), used_all + used
        u = Z[:n_x]
        x_end, v_end = cX + k[0] * u, cV + k[1] * u
        error = sum((h**2 * d) * A_j for d, A_j in zip(sc.error_weights, stage_accelerations) if d != 0.0)
        ends = (x_end, v_end, P[:, -1], PD[:, -1], PDD[:, -1], damping, mask, data)
        new_state = ca.vertcat(x_end, v_end, self._filtered(error, k, factors, ends), u, Z[n_x:])
        monitor = ca.vertcat(monitor[:2], power, monitor[6:])
        return new_state, monitor, norm, used_all, factors

    def _filtered(self, error, k, factors: Factors, ends) -> ca.MX:
        """The embedded estimate e filtered as W^-1 M e (Hairer and Wanner, Sec. IV.8, for stiff
        problems), with W = M + h gamma C + h^2 gamma^2 K the stages' Newton matrix (the window's
        factors): e itself where the motion is resolved, and e over (h gamma omega)^2 on the
        stiff modes, which the raw difference of a stiffly accurate scheme and its embedded one
        overstates by that factor. M e is the residual's change when the accelerations change
        by e at the step's end positions and velocities (two evaluations and a solve a step)."""
        sys, n_x = self.system, self.state.n_x
        x_end, v_end, p, pdot, pddot, damping, mask, data = ends
        # velocities held (kv = 0), positions held by moving the affine part against kx u: the
        # rows change by M e only (the equalities' rows, g / kx, not at all)
        k_held = ca.vertcat(k[0], 0, 1, k[3])
        evaluations = []
        for u in (ca.MX.zeros(n_x), error):
            affine = (x_end - k[0] * u, v_end, ca.MX.zeros(n_x))
            si = sys.step_inputs(affine, k_held, p, pdot, pddot, damping, mask, data)
            Z = ca.vertcat(u, ca.MX.zeros(sys.n_z - n_x))
            evaluations.append(
                Evaluation.of(self.stage_evaluation(*factors.kept_reverse, *si.parts(), Z), self.n_groups)
            )
        before, after = evaluations
        change = Evaluation(
            [a - b for a, b in zip(after.y, before.y)], after.rhs - before.rhs, *after.parts()[self.n_groups + 1 :]
        )
        return sys.solve(change, ca.MX(1), factors)[:n_x]


def predictor(nodes: tuple[float, ...], i: int) -> list[tuple[int, float]]:
    """Stage i's first guess of its unknowns as weights of the known ones (0: the step's start,
    j + 1: stage j): the line through the two known nodes nearest c_i."""
    known = [0.0, *nodes[:i]]
    order = sorted(range(len(known)), key=lambda j: abs(known[j] - nodes[i]))
    if len(known) == 1:
        return [(order[0], 1.0)]
    a, b = order[:2]
    w = (nodes[i] - known[a]) / (known[b] - known[a])
    return [(a, 1.0 - w), (b, w)]
