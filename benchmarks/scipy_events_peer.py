"""The peer of flexmech's event-driven impact runs in benchmarks/impacts.py: the same compliant
contact model (the same right-hand side: flexure, gravity, the Lankarani-Nikravesh normal law
with its impact speed frozen at onset, Ambrosio's friction) integrated by a general
integrator, scipy's solve_ivp (RK45, Dormand-Prince 5(4) like flexmech's), with its events
located by solve_ivp itself. Each terminal event flips its flag as flexmech does (a contact
onset freezes the impact speed and sets the slip flags from the slip speed) and the
integration restarts there. The model's functions are CasADi's, called from Python per
evaluation: the integrator is the peer, not the model.
"""

from __future__ import annotations

import time

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from flexmech.models.impacts.model import WORKS, ImpactModel
from flexmech.service.impacts.event_driven import MIN_IMPACT_SPEED, rhs_function, violations


class ScipyEvents:
    def __init__(self, model: ImpactModel, p: np.ndarray):
        self.n, self.P = model.bodies.size, len(model.pairs)
        n, P = self.n, self.P
        rhs = rhs_function(model)
        y = ca.SX.sym("y", 2 * n + len(WORKS))
        t, flags = ca.SX.sym("t"), ca.SX.sym("flags", 4 * P)
        contact, b0, b1, speed = (flags[k * P : (k + 1) * P] for k in range(4))
        ydot, switching, _, _, rate, v_T, _ = rhs(y[:n], y[n : 2 * n], t, contact, b0, b1, speed, model.p)
        self._f = ca.Function("f", [t, y, flags, model.p], [ydot])
        self._g = ca.Function(
            "g", [t, y, flags, model.p], [violations(model, switching, contact, b0, b1), rate, ca.fabs(v_T)]
        )
        self.p = p
        levels = ca.Function(
            "levels",
            [model.p],
            [ca.vertcat(*[pair.v0 for pair in model.pairs]), ca.vertcat(*[pair.v1 for pair in model.pairs])],
        )
        self.v0, self.v1 = (np.asarray(x).ravel() for x in levels(p))  # Ambrosio's slip speeds

    def run(self, q0, v0, until: float, rtol: float, atol: np.ndarray, max_step: float) -> dict:
        """Integrate to `until`: states at solve_ivp's steps, the contact onsets (time, impact
        speed), the steps taken and the seconds."""
        P = self.P
        flags = np.zeros(4 * P)
        y = np.concatenate([q0, v0, np.zeros(len(WORKS))])
        tol = np.concatenate([atol, np.full(len(WORKS), 1e300)])  # the works ride along, uncontrolled
        t, steps, onsets = 0.0, 0, []
        times, states = [0.0], [y.copy()]
        began = time.perf_counter()
        while t < until * (1 - 1e-15):

            def fun(s, state, flags=flags):
                return np.asarray(self._f(s, state, flags, self.p)).ravel()

            events = []
            for k in range(3 * P):

                def event(s, state, k=k, flags=flags):
                    return float(self._g(s, state, flags, self.p)[0][k])

                event.terminal, event.direction = True, 1
                events.append(event)
            sol = solve_ivp(fun, (t, until), y, method="RK45", rtol=rtol, atol=tol, max_step=max_step, events=events)
            steps += len(sol.t) - 1
            times += sol.t[1:].tolist()
            states += list(sol.y[:, 1:].T)
            t, y = float(sol.t[-1]), sol.y[:, -1].copy()
            if sol.status != 1:
                if sol.status < 0:
                    raise RuntimeError(f"solve_ivp failed at t = {t}: {sol.message}")
                break
            fired = [k for k, hits in enumerate(sol.t_events) if len(hits)]
            _, rate, slip = (np.asarray(x).ravel() for x in self._g(t, y, flags, self.p))
            flags = flags.copy()
            for k in fired:
                pair, kind = divmod(k, 3)  # per pair: contact, beyond v0, beyond v1
                if kind == 0 and flags[pair] < 0.5:  # a contact onset
                    flags[pair] = 1.0
                    flags[P + pair] = float(slip[pair] > self.v0[pair])
                    flags[2 * P + pair] = float(slip[pair] > self.v1[pair])
                    flags[3 * P + pair] = max(rate[pair], MIN_IMPACT_SPEED)
                    onsets.append((t, float(rate[pair])))
                elif kind == 0:
                    flags[pair] = 0.0
                else:
                    slot = (1 if kind == 1 else 2) * P + pair
                    flags[slot] = 1.0 - flags[slot]
        return {
            "times": np.array(times),
            "states": np.array(states),
            "onsets": onsets,
            "steps": steps,
            "seconds": time.perf_counter() - began,
        }
