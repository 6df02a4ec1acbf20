"""A link simulation to an accuracy target (`simulate.accuracy`): the run refines its links'
elements and its time steps until the named outputs' estimated errors are within the target,
and reports each output's estimate.

A run's error has two parts, the links' elements (space) and the time steps, and each is
estimated by one refinement of that part alone: the same run with every link's elements
doubled, and with its steps halved (adaptive steps: their tolerance divided by
TOLERANCE_FACTOR). A part's estimate for an output is the largest difference between the run
and its refinement at the run's kept times (the refinement keeps every step and is
interpolated by a cubic spline, exact at the times a halved fixed step shares), relative to the
output's largest excursion from its start value in the refinement. The run's estimate is the
space part plus TIME_SAFETY times the time part: the run's own error where a refinement of the
elements removes most of its part (cubic elements converge fast) and one of the steps at least
half of it. A sudden release excites modes that no practical step resolves, and their share
of the error falls only as h^1.1-2.2 (benchmarks/release_spectrum.py): on the rod's release
(0.3 s, generalized-alpha, against sdirk4 at 16 elements and 62.5 us) the plain sum of the two
differences was 0.82 and 0.95 of the error at 4 elements (1 and 2 ms), 1.16 and 1.73 at 2
(4 and 2 ms); the factor covers the first.

The run starts from the document's own elements and steps (its a priori choice). Over the
target, every part whose estimate is above half of it is refined by what its order predicts
brings it under half (a power of 2 up to MAX_JUMP: the elements' order 4, the scheme's, or
after two checks the order observed between them), the larger one by 2 where neither is, and
the new run is checked in turn, for at most ROUNDS rounds; each run stays under the step limit
and the caller's stop. A target still missed is a result: status
`accuracy_not_reached`, with the estimates and every run made."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from pydantic import ValidationError
from scipy.interpolate import CubicSpline

from flexmech.models import Mechanism, MechanismError, compile_mechanism
from flexmech.models.documents.simulation_spec import SimulateSpec
from flexmech.models.elements import FAMILIES

ROUNDS = 6  # of checks; the step limit bounds them too
SPACE_FACTOR = 2  # a check's elements per link element
STEP_FACTOR = 2  # fixed steps: a check's steps per step
TOLERANCE_FACTOR = 10.0  # adaptive steps: a check's tolerance is the run's over this
TIME_SAFETY = 2.0  # the time part's estimate over its difference: a refinement that halves it (see above)
MAX_JUMP = 8  # the most one round multiplies the elements, or divides the step, by
SPACE_ORDER = 4.0  # cubic elements' displacements: error ~ (element length)^4
TIME_ORDERS = {"sdirk4": 4.0}  # the schemes' orders; the others 2
CONTROLLER_ORDERS = {"sdirk4": 4.0}  # adaptive steps: h ~ tolerance^(1/this); the others 3


@dataclass(frozen=True)
class Plan:
    """A run's discretization: each link's element count (by element name), and its fixed step
    or its adaptive steps' tolerance."""

    intervals: tuple[tuple[str, int], ...]
    step: float
    tolerance: float | None  # None: fixed steps

    def finer_time(self, factor: float = STEP_FACTOR, controller: float = 3.0) -> Plan:
        """Steps `factor` times shorter: fixed ones divided, an adaptive tolerance divided by
        factor^controller (and at least by TOLERANCE_FACTOR)."""
        if self.tolerance is None:
            return replace(self, step=_rounded(self.step / factor))
        divisor = TOLERANCE_FACTOR if factor == STEP_FACTOR else max(TOLERANCE_FACTOR, factor**controller)
        return replace(self, tolerance=_rounded(self.tolerance / divisor))

    def time_refinement(self) -> str:
        return f"step / {STEP_FACTOR}" if self.tolerance is None else f"tolerance / {TOLERANCE_FACTOR:g}"

    def finer_space(self, mech: Mechanism, factor: int = SPACE_FACTOR) -> Plan | None:
        """Every link's elements times `factor` (the largest power of 2 up to it that every link's
        document allows); None where even a doubling is over a link's limit (or the mechanism
        has no link elements)."""
        while factor >= SPACE_FACTOR and self.intervals:
            refined = tuple((name, factor * n) for name, n in self.intervals)
            if all(_allowed(mech, name, n) for name, n in refined):
                return replace(self, intervals=refined)
            factor //= 2
        return None

    def summary(self) -> dict:
        if self.tolerance is None:
            return {"intervals": dict(self.intervals), "step": self.step}
        return {"intervals": dict(self.intervals), "tolerance": self.tolerance}


def _rounded(value: float) -> float:
    """To 12 digits: a tenth of 1e-5 is 1e-6, not 1.0000000000000002e-06, in the report."""
    return float(f"{value:.12g}")


def _allowed(mech: Mechanism, name: str, intervals: int) -> bool:
    element = mech.document.elements[name]
    try:
        type(element).model_validate({**element.model_dump(exclude_unset=True), "intervals": intervals})
    except ValidationError:
        return False
    return True


def jump(part: float, allowed: float, order: float) -> int:
    """The refinement (a power of 2, from 2 to MAX_JUMP) that brings `part` under `allowed` where
    it falls as the refinement^order."""
    if not math.isfinite(part) or part <= allowed:
        return 2
    return int(min(MAX_JUMP, 2 ** math.ceil(math.log2((part / allowed) ** (1 / order)))))


def observed_order(before: float, after: float, refinement: float, nominal: float) -> float:
    """The order a part fell at between two checks (refinement: of elements or of steps), within
    [1, nominal]; nominal where it did not change."""
    if refinement <= 1 or before <= 0 or after <= 0 or not math.isfinite(before / after):
        return nominal
    return min(nominal, max(1.0, math.log(before / after) / math.log(refinement)))


def link_intervals(mech: Mechanism) -> tuple[tuple[str, int], ...]:
    """The element count of every link that runs as a chain of element kernels (the links a
    simulation moves, models.kernels)."""
    chains = [t for t in mech.structure.elements if getattr(FAMILIES.of(t), "kernel_chain", False)]
    return tuple((t.name, t.intervals) for t in chains)


def mechanism_of(mech: Mechanism, plan: Plan) -> Mechanism:
    """The mechanism with the plan's element counts, and the same values of every numeric field
    (a request's values over the document's are kept)."""
    if plan.intervals == link_intervals(mech):
        return mech
    elements = dict(mech.document.elements)
    for name, n in plan.intervals:
        elements[name] = elements[name].model_copy(update={"intervals": n})
    refined = compile_mechanism(mech.document.model_copy(update={"elements": elements}))
    values = {p.pointer: v for p, v in zip(mech.parameters, mech.si_values)}
    si = np.array([values.get(p.pointer, v) for p, v in zip(refined.parameters, refined.si_values)])
    return replace(refined, si_values=si)


def differences(run: dict, finer: dict, names: list[str]) -> dict[str, float]:
    """Per output: the largest |run - finer| at the run's kept times, relative to the output's
    largest excursion from its start in `finer` (its size where it does not move; 1 where that is
    zero too)."""
    times, finer_times = np.asarray(run["times"], float), np.asarray(finer["times"], float)
    rising = np.concatenate(([True], np.diff(finer_times) > 0))
    out = {}
    for name in names:
        y, fine = (np.asarray(r["outputs"][name], float) for r in (run, finer))
        if not (np.isfinite(y).all() and np.isfinite(fine).all()) or rising.sum() < 2:
            out[name] = math.inf
            continue
        difference = float(np.abs(y - CubicSpline(finer_times[rising], fine[rising])(times)).max())
        excursion, size = float(np.abs(fine - fine[0]).max()), float(np.abs(fine).max())
        scale = excursion if excursion > 1e-9 * size else (size or 1.0)
        out[name] = difference / scale
    return out


class AccuracyRuns:
    """The runs of one simulation to an accuracy target, by `run(mech, spec) -> (history,
    report)` (service.dynamics.run.run_simulation without a target)."""

    def __init__(self, mech: Mechanism, spec: SimulateSpec, run):
        if spec.outputs is None:
            raise MechanismError(
                "/simulate/outputs",
                'an accuracy target is on the named outputs: name them (e.g. ["bodies.tip.x", "bodies.tip.y"])',
            )
        self.mech, self.spec, self._run = mech, spec, run
        self.names = list(spec.outputs)
        self.target = float(spec.accuracy or 0.0)
        self.log: list[dict] = []
        self.rounds: list[tuple[Plan, float, float]] = []  # each check's plan and worst parts
        self._made: dict[tuple, tuple] = {}  # (plan, every, shapes) -> (history, report)
        self._mechanisms: dict[tuple, Mechanism] = {}  # by element counts: compiled once

    def run(self, plan: Plan, role: str, check: bool = False) -> tuple:
        """One run of the plan (its fixed step, or its adaptive steps' tolerance), logged. A
        check keeps every step (compared through a spline) and no shapes (nothing draws it)."""
        kept = {"every": 1, "shapes": False} if check else {"every": self.spec.every, "shapes": self.spec.shapes}
        key = (plan, kept["every"], kept["shapes"])
        if key in self._made:  # a check's refinement that became the run
            return self._made[key]
        steps = {"step": plan.step} if plan.tolerance is None else {"tolerance": plan.tolerance}
        spec = self.spec.model_copy(update={"accuracy": None, **steps, **kept})
        if plan.intervals not in self._mechanisms:
            self._mechanisms[plan.intervals] = mechanism_of(self.mech, plan)
        try:
            history, report = self._run(self._mechanisms[plan.intervals], spec)
        except MechanismError as exc:
            if exc.pointer != "/simulate/step" or not self.log:  # the first run's own limit: the document's error
                raise
            history, report = None, {"status": "step_limit", "message": exc.problem, "steps": 0, "seconds": 0.0}
        self.log.append(
            {
                **plan.summary(),
                "role": role,
                "status": report["status"],
                "steps": report["steps"],
                "seconds": report["seconds"],
            }
        )
        self._made[key] = (history, report)
        return history, report

    def checks(self, plan: Plan, report: dict) -> tuple[dict, dict, dict | None]:
        """(space part, time part, a failed refinement's report or None) of the run's error."""
        self._made = {}  # this round's refinements alone: a run's history is large
        time_plan, space_plan = plan.finer_time(), plan.finer_space(self.mech)
        _, by_time = self.run(time_plan, time_plan.time_refinement(), check=True)
        if by_time["status"] != "finished":
            return {}, {}, by_time
        space = dict.fromkeys(self.names, 0.0)
        if space_plan is not None:
            _, by_space = self.run(space_plan, f"elements x {SPACE_FACTOR}", check=True)
            if by_space["status"] != "finished":
                return {}, {}, by_space
            space = differences(report, by_space, self.names)
        return space, differences(report, by_time, self.names), None

    def refined(self, plan: Plan, space: dict, time: dict) -> Plan | None:
        """The next plan: each part over half the target refined by what its order predicts
        brings it under (jump), the larger one by 2 where neither is over; None when that is
        the elements' and a link is at its limit."""
        parts = max(space.values(), default=0.0), TIME_SAFETY * max(time.values(), default=0.0)
        self.rounds.append((plan, *parts))
        space_order, time_order = self.orders()
        allowed = self.target / 2
        over_space, over_time = parts[0] > allowed, parts[1] > allowed
        if not (over_space or over_time):  # their sum is over the target
            over_space, over_time = parts[0] >= parts[1], parts[0] < parts[1]
        finer = plan.finer_space(self.mech, jump(parts[0], allowed, space_order)) if over_space else plan
        if finer is None:
            return None
        if not over_time:
            return finer
        return finer.finer_time(jump(parts[1], allowed, time_order), CONTROLLER_ORDERS.get(self.spec.scheme, 3.0))

    def orders(self) -> tuple[float, float]:
        """(elements', steps') orders: as observed between the last two checks where a part was
        refined, else nominal (SPACE_ORDER, the scheme's)."""
        nominal = SPACE_ORDER, TIME_ORDERS.get(self.spec.scheme, 2.0)
        if len(self.rounds) < 2:
            return nominal
        (before, space_before, time_before), (after, space_after, time_after) = self.rounds[-2:]
        elements = after.intervals[0][1] / before.intervals[0][1] if after.intervals else 1.0
        if after.tolerance is None:
            steps = before.step / after.step
        else:
            steps = (before.tolerance / after.tolerance) ** (1 / CONTROLLER_ORDERS.get(self.spec.scheme, 3.0))
        return (
            observed_order(space_before, space_after, elements, nominal[0]),
            observed_order(time_before, time_after, steps, nominal[1]),
        )


def run_to_accuracy(mech: Mechanism, spec: SimulateSpec, run, stop=None) -> tuple:
    """(history, report) of the run that meets spec.accuracy on its named outputs, or of the last
    one tried; report["accuracy"] holds the estimates and every run made."""
    runs = AccuracyRuns(mech, spec, run)
    plan = Plan(link_intervals(mech), spec.step, spec.tolerance if spec.adaptive else None)
    history, report = runs.run(plan, "run")
    if report["status"] != "finished":  # the document's own run: its status as it is
        return history, _with_accuracy(report, runs, plan, {}, {}, None)
    for round in range(ROUNDS):
        space, time, failed = runs.checks(plan, report)
        if failed is not None:
            return history, _with_accuracy(report, runs, plan, {}, {}, failed)
        met = max(space[n] + TIME_SAFETY * time[n] for n in runs.names) <= runs.target
        finer = runs.refined(plan, space, time)
        if met or finer is None or round == ROUNDS - 1 or (stop is not None and stop()):
            break
        finer_history, finer_report = runs.run(finer, "run")
        if finer_report["status"] != "finished":  # this run and its estimates stand
            return history, _with_accuracy(report, runs, plan, space, time, finer_report)
        plan, history, report = finer, finer_history, finer_report
    return history, _with_accuracy(report, runs, plan, space, time, None)


def _with_accuracy(report: dict, runs: AccuracyRuns, plan: Plan, space: dict, time: dict, failed) -> dict:
    estimates = {n: space[n] + TIME_SAFETY * time[n] for n in runs.names} if space and time else {}
    met = bool(estimates) and max(estimates.values()) <= runs.target
    out = {
        **report,
        "accuracy": {
            "target": runs.target,
            "met": met,
            "estimated_errors": estimates,
            "space_errors": space,
            "time_errors": time,
            **plan.summary(),
            "runs": runs.log,
            "seconds": sum(r["seconds"] for r in runs.log),
        },
    }
    if report["status"] != "finished" or met:
        return out
    if failed is not None:
        estimated = f" (estimated error {max(estimates.values()):.2g})" if estimates else ""
        why = f"a finer run ({failed['status']}: {failed['message']}) did not finish{estimated}"
    else:  # checked, and over the target at its last check
        worst = max(estimates, key=estimates.__getitem__)
        why = (
            f"the estimated error of {worst} is {estimates[worst]:.2g} (elements {space[worst]:.2g}, steps "
            f"{time[worst]:.2g}) after {len(runs.log)} runs"
        )
    out["status"] = "accuracy_not_reached"
    out["message"] = (
        f"the accuracy target {runs.target:g} was not reached: {why}; the report is of the run at {plan.summary()}"
    )
    return out
