"""Located contact onsets in link dynamics. A damped normal law (models.contact.pair_forces:
Hunt-Crossley, Lankarani-Nikravesh, Flores) reads the approach speed at its contact's onset,
qdot_minus, so a run steps onto each onset: a step whose end is in contact while its start is not is replaced by
a step to the onset, whose length the Illinois method finds (the indentation at the end of a
step of that length from the same start is zero), and a step over the rest of the interval.
From then on the pair's onset speed (a parameter of the graphs) is the approach speed
measured at the onset. Hertz's force vanishes at the onset and reads no speed: its pairs need
no location.

The indentations and their rates come from the run's states by a small Function of the free
body coordinates, their rates, p and the rates of the moving parameters."""

from __future__ import annotations

import casadi as ca
import numpy as np

from flexmech.models.contact.elastic_pairs import DAMPED_LAWS, elastic_pairs
from flexmech.models.contact.pair_forces import contact_forces
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.structure import Structure
from flexmech.service.dynamics.engine import WINDOW_ACCEPTANCE

GRID_SLACK = 1e-10  # of the step: the onset is located within this much of it (and a rest this short is none)
LANDING_ITERATIONS = 60
MIN_APPROACH = 1e-12  # document length per second: a grazing onset's speed (the damped laws divide by it)


class Onsets:
    """The damped pairs of a structure: their indentations, and their onset speeds as set so far."""

    def __init__(self, structure: Structure, moving: tuple[int, ...]):
        topology = structure.contacts
        pairs = (
            []
            if topology is None
            else [pair for pair in topology.pairs if pair.potential and pair.normal_law in DAMPED_LAWS]
        )
        self.names = [pair.name for pair in pairs]
        self.speed_rows = [structure.index.get(f"{pair.pointer}/normal/onset_speed") for pair in pairs]
        self.structure, self.moving = structure, moving
        self.n_free = len(structure.free)
        self.gaps = _gap_function(structure, moving, self.names) if pairs else None
        self._forces = None

    def __bool__(self) -> bool:
        return bool(self.names)

    def indentations(self, states: np.ndarray, n_x: int, P: np.ndarray, PD: np.ndarray) -> tuple[np.ndarray, ...]:
        """(q, qdot) per pair (rows) and state (columns; document length and length per second)."""
        x, v = states[: self.n_free], states[n_x : n_x + self.n_free]
        q, qdot = self.gaps.map(states.shape[1])(x, v, P, PD)
        return np.asarray(q), np.asarray(qdot)

    def normal_forces(self, x: np.ndarray, v: np.ndarray, P: np.ndarray, PD: np.ndarray) -> dict[str, np.ndarray]:
        """Per damped pair, its whole normal force (elastic and damping, document force units)
        at states of free coordinates x, their rates v (columns), P and the moving rates PD."""
        if self._forces is None:
            self._forces = _force_function(self.structure, self.moving, self.names)
        values = np.asarray(self._forces.map(x.shape[1])(x, v, P, PD)).reshape(len(self.names), -1)
        return dict(zip(self.names, values))

    def first_crossing(self, before: np.ndarray, after: np.ndarray) -> tuple[int, int] | None:
        """(step, pair) of the first step whose start is out of contact and its end in it, from
        the indentations at each step's start (before) and end (after); None if no step is."""
        entering = (before <= 0) & (after > 0)
        steps = np.flatnonzero(entering.any(axis=0))
        if not len(steps):
            return None
        return int(steps[0]), int(np.flatnonzero(entering[:, steps[0]])[0])

    def apply(self, P: np.ndarray, speeds: list[float]) -> np.ndarray:
        """P with the pairs' onset speeds in their rows (every column)."""
        P = np.array(P, dtype=float)
        for row, speed in zip(self.speed_rows, speeds):
            if row is not None:
                P[row, :] = speed
        return P


def _symbols(structure: Structure, moving: tuple[int, ...]):
    """(ctx, x, v, pdot, the rates of every parameter) of the free coordinates' Functions."""
    ctx = AssemblyContext(structure)
    n_free = len(structure.free)
    x, v, pdot = ca.SX.sym("x", n_free), ca.SX.sym("v", n_free), ca.SX.sym("pdot", len(moving))
    rates = ca.SX.zeros(ctx.p.numel())
    for k, index in enumerate(moving):
        rates[index] = pdot[k]
    return ctx, x, v, pdot, rates


def _gap_function(structure: Structure, moving: tuple[int, ...], names: list[str]) -> ca.Function:
    ctx, x, v, pdot, rates = _symbols(structure, moving)
    pairs = {pair.name: pair for pair in elastic_pairs(ctx, ctx.displacements(x))}
    q = ca.vertcat(*[pairs[name].indentation for name in names])
    qdot = ca.jtimes(q, x, v) + ca.jtimes(q, ctx.p, rates)
    return ca.Function("indentations", [x, v, ctx.p, pdot], [q, qdot], ["x", "v", "p", "pdot"], ["q", "qdot"])


def _force_function(structure: Structure, moving: tuple[int, ...], names: list[str]) -> ca.Function:
    ctx, x, v, pdot, rates = _symbols(structure, moving)
    d = ctx.displacements(x)
    body_rates = [ca.jtimes(db, x, v) + ca.jtimes(db, ctx.p, rates) for db in d]
    forces = contact_forces(ctx, d, body_rates).normal_forces
    return ca.Function("normal_forces", [x, v, ctx.p, pdot], [ca.vertcat(*[forces[name] for name in names])])


def crossing(runner, at, inputs, S, settled: int) -> tuple[int, int, float] | None:
    """(step, pair, indentation at its end) of the window's first settled step that enters a
    damped pair's contact; None if none does."""
    onsets = runner.onsets
    if not onsets or S is None or settled == 0:
        return None
    P, PD = (q if np.ndim(q) == 2 else np.asarray(q, dtype=float)[:, None] for q in inputs[:2])  # or one step's
    after, _ = onsets.indentations(S[:, :settled], runner.n, P[:, :settled], PD[:, :settled])
    before = np.column_stack([runner.indentations_at(at), after[:, :-1]])
    found = onsets.first_crossing(before, after)
    return None if found is None else (found[0], found[1], float(after[found[1], found[0]]))


def step_onto_onset(runner, history, at, pair: int, q_end: float, h: float):
    """The Resume after the step h from `at`, taken as a step onto the onset of `pair`'s contact
    and a step over the rest of h (itself landing on any other onset it meets)."""
    found = _locate(runner, at, pair, q_end, h)
    if found is None:
        history.status = "not_converged"
        history.message = (
            f"the onset of contact '{runner.onsets.names[pair]}' after t = {at.time:g} s could not be "
            "located: try a smaller step"
        )
        return at
    state, monitor, p_end, tau, approach = found
    speeds = list(runner.speeds(at))
    speeds[pair] = max(approach, MIN_APPROACH)
    rest = h - tau
    onset = runner.advance(
        history,
        at,
        state,
        monitor,
        tau,
        p=p_end,
        time=at.time + tau,
        kept=True,
        speeds=speeds,
        inserted=at.inserted + (1 if rest > GRID_SLACK * h else 0),
    )
    if rest <= GRID_SLACK * h:
        return onset
    trial = _trial(runner, onset, rest)
    if trial is None:
        history.status = "not_converged"
        history.message = (
            f"the step after the contact onset at t = {onset.time:g} s did not converge: try a smaller step"
        )
        return onset
    state, monitor, inputs = trial
    entering = crossing(runner, onset, inputs, state[:, None], 1)
    if entering is not None:
        return step_onto_onset(runner, history, onset, entering[1], entering[2], rest)
    return runner.advance(history, onset, state, monitor, rest, p=inputs[0][:, 0])


def _locate(runner, at, pair: int, q_end: float, h: float):
    """(state, monitor, p, step length, approach speed) at the first state in contact within
    GRID_SLACK of the onset: the Illinois method on the step's length, bracketed by the step's
    start (out of contact) and end (in contact); None if a trial step does not settle."""
    q_start = float(runner.indentations_at(at)[pair])
    lo, f_lo, hi, f_hi, last = 0.0, q_start, h, q_end, 0
    inside, inside_q = None, q_end  # the latest trial that ended in contact, and its indentation
    for _ in range(LANDING_ITERATIONS):
        tau = hi - f_hi * (hi - lo) / (f_hi - f_lo)
        trial = _trial(runner, at, tau)
        if trial is None:
            return None
        state, monitor, inputs = trial
        q, qdot = runner.onsets.indentations(state[:, None], runner.n, inputs[0][:, :1], inputs[1][:, :1])
        f = float(q[pair, 0])
        if f > 0:
            inside, inside_q = (state, monitor, inputs[0][:, 0], tau, float(qdot[pair, 0])), f
            hi, f_hi = tau, f
            f_lo, last = (f_lo / 2 if last == 1 else f_lo), 1
        else:
            lo, f_lo = tau, f
            f_hi, last = (f_hi / 2 if last == -1 else f_hi), -1
        if hi - lo <= GRID_SLACK * h or (inside is not None and inside_q <= 1e-12 * (q_end - q_start)):
            break
    if inside is None:  # every trial fell short: the whole step is the one that enters
        trial = _trial(runner, at, h)
        if trial is None:
            return None
        state, monitor, inputs = trial
        q, qdot = runner.onsets.indentations(state[:, None], runner.n, inputs[0][:, :1], inputs[1][:, :1])
        inside = (state, monitor, inputs[0][:, 0], h, float(qdot[pair, 0]))
    return inside


def _trial(runner, at, h: float):
    """(state, monitor, the step's inputs) of one step h from `at`, by full Newton where the
    window's chord iterations do not settle it (a trial in contact still damps with the last
    onset's speed, which may be far off); None if neither does."""
    inputs, S, monitors, _, settled = runner.run_window(at, h, 1)
    if S is not None and settled >= 1:
        return S[:, 0], monitors[:, 0], inputs
    state, monitor, norm = runner.rescue(at, tuple(q[:, 0] for q in inputs), h)
    return (state, monitor, inputs) if norm <= WINDOW_ACCEPTANCE else None
