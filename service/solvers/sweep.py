"""Load sweeps with continuation, and the target analysis (which load gives an output value).

A sweep varies one numeric field along a path of values; each point starts Newton from the
previous converged solution ("previous", default) or from the undeformed state
("undeformed"), the paper's two restart strategies. A failed point is recorded with its
status and the sweep goes on from the last converged point.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Literal

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.documents.document import SweepSpec
from flexmech.models.graph.assembly import Graphs
from flexmech.models.units import quantity_to_si
from flexmech.service.solvers.equilibrium import EquilibriumResult, NewtonOptions, check_constrained, newton
from flexmech.service.solvers.newton import iterate_dense
from flexmech.service.units import residual_report

Start = Literal["previous", "undeformed"]


@dataclass
class SweepResult:
    path: str
    values: np.ndarray  # document units
    status: list[str]
    iterations: np.ndarray
    solver_residuals: np.ndarray  # nondimensional, every row (service.units.residual_report)
    z: np.ndarray  # (points, n_free), nondimensional
    outputs: dict[str, np.ndarray]  # document units, one entry per point
    seconds: float
    mechanism: Mechanism = field(repr=False)

    def residuals(self, point: int) -> dict:
        """service.units.residual_report of one point."""
        mech = self.mechanism.with_values({self.path: float(self.values[point])})
        return residual_report(mech, self.z[point])

    @property
    def all_converged(self) -> bool:
        return all(s == "converged" for s in self.status)

    def to_dict(self) -> dict:
        return {
            "path": self.path,
            "values": self.values.tolist(),
            "status": self.status,
            "iterations": self.iterations.tolist(),
            "seconds": self.seconds,
            "outputs": {k: v.tolist() for k, v in self.outputs.items()},
        }


def sweep(
    mech: Mechanism,
    path: str,
    values,
    options: NewtonOptions = NewtonOptions(),
    start: Start = "previous",
    progress=None,
) -> SweepResult:
    """Solve the equilibrium for each value of the numeric field `path` (document units).

    progress(done, total) is called after each point when given.
    """
    if start not in ("previous", "undeformed"):
        raise ValueError(f"start: unknown strategy '{start}' (previous, undeformed)")
    values = np.asarray(values, dtype=float).ravel()
    k = mech.parameter_index(path)
    factor = mech.nd_per_doc(mech.parameters[k].kind)
    p = mech.p()
    check_constrained(mech, p)
    started = time.perf_counter()
    n = mech.n_free
    frozen = None
    if options.jacobian == "frozen":
        frozen = np.asarray(mech.graphs.residual_and_tangent(np.zeros(n), p)[1])
    z_prev = np.zeros(n)
    Z = np.zeros((len(values), n))
    status, iterations, norms = [], np.zeros(len(values), dtype=int), np.zeros(len(values))
    Y = []
    for i, v in enumerate(values):
        p = p.copy()
        p[k] = v * factor
        guess = z_prev if start == "previous" else np.zeros(n)
        r = newton(mech, p, guess, options, frozen)
        if r.converged:
            z_prev = r.z
        Z[i], iterations[i], norms[i] = r.z, r.iterations, r.solver_residual
        status.append(r.status)
        Y.append(np.asarray(mech.graphs.outputs(r.z, p)).ravel())
        if progress is not None:
            progress(i + 1, len(values))
    Y = np.array(Y).reshape(len(values), -1)
    names, kinds = mech.graphs.output_names, mech.graphs.output_kinds
    outputs = {name: Y[:, j] / mech.nd_per_doc(kind) for j, (name, kind) in enumerate(zip(names, kinds))}
    return SweepResult(path, values, status, iterations, norms, Z, outputs, time.perf_counter() - started, mech)


@lru_cache(maxsize=32)
def target_function(graphs: Graphs, parameter: int, output: int, n_free: int, n_params: int) -> ca.Function:
    """(x=[z; lambda], p, target) -> (G, dG/dx): equilibrium with parameter `parameter` set to
    lambda, and output `output` equal to target."""
    x = ca.SX.sym("x", n_free + 1)
    p = ca.SX.sym("p", n_params)
    target = ca.SX.sym("target")
    z, lam = x[:n_free], x[n_free]
    e = ca.DM.zeros(n_params)
    e[parameter] = 1
    p_mod = p + (lam - p[parameter]) * e
    G = ca.vertcat(graphs.residual(z, p_mod), graphs.outputs(z, p_mod)[output] - target)
    return ca.Function(
        "target_system", [x, p, target], [G, ca.jacobian(G, x)], ["x", "p", "target"], ["G", "J"], dict(cse=True)
    )


@dataclass
class TargetResult:
    status: str
    value: float  # the field's value that reaches the target, document units
    equilibrium: EquilibriumResult


def solve_for_target(
    mech: Mechanism, path: str, output: str, target: float, options: NewtonOptions = NewtonOptions()
) -> TargetResult:
    """Find the value of numeric field `path` for which `output` equals `target` (both in
    document units), e.g. the actuation force that closes the gripper. Newton on the
    equilibrium equations augmented with the output condition, from the current value."""
    names = mech.graphs.output_names
    if output not in names:
        named = ", ".join(n for n in names if not n.startswith(("elements.", "bodies.", "reactions.")))
        raise MechanismError(
            "output",
            f"unknown output '{output}' (named outputs: {named or 'none'}; also bodies.*, reactions.*, elements.*)",
        )
    k = mech.parameter_index(path)
    m = names.index(output)
    f = target_function(mech.graphs, k, m, mech.n_free, len(mech.parameters))
    p = mech.p()
    check_constrained(mech, p)
    start = newton(mech, p, np.zeros(mech.n_free), options)
    factor = mech.nd_per_doc(mech.parameters[k].kind)
    out_factor = mech.nd_per_doc(mech.graphs.output_kinds[m])
    t_nd = target * out_factor

    def evaluate(x):
        G, Jx = f(x, p, t_nd)
        return np.asarray(G).ravel(), np.asarray(Jx)

    x0 = np.concatenate([start.z, [p[k]]])
    full = replace(options, jacobian="full")
    started = time.perf_counter()
    status, x, norm, iters, history, message = iterate_dense(evaluate, x0, full)
    seconds = time.perf_counter() - started + start.seconds
    value = float(x[-1] / factor)
    solved = mech.with_values({path: value})
    eq = EquilibriumResult(status, x[:-1], norm, iters, history, seconds, solved, message)
    return TargetResult(status, value, eq)


def sweep_values(start: float, stop: float, steps: int) -> np.ndarray:
    """`steps` equal steps from start to stop: steps + 1 values."""
    return np.linspace(start, stop, steps + 1)


def run_sweep_spec(
    mech: Mechanism, spec: SweepSpec, options: NewtonOptions = NewtonOptions(), start: Start = "previous", progress=None
) -> tuple[SweepResult | None, TargetResult | None]:
    """Run a load path: `spec.path` from `spec.start` to `spec.stop`, or, with `spec.until`, to
    the value found by solve_for_target. A target that is not reached is a result too:
    (None, the unconverged TargetResult)."""
    first = _doc_value(mech, spec.start, mech.parameter_kind(spec.path), "/sweep/start")
    target = None
    if spec.until is not None:
        names = mech.graphs.output_names
        if spec.until.output not in names:
            raise MechanismError("/sweep/until/output", f"unknown output '{spec.until.output}'")
        out_kind = mech.graphs.output_kinds[names.index(spec.until.output)]
        goal = _doc_value(mech, spec.until.equals, out_kind, "/sweep/until/equals")
        target = solve_for_target(mech, spec.path, spec.until.output, goal, options)
        if target.status != "converged":
            return None, target
        last = target.value
    else:
        last = _doc_value(mech, spec.stop, mech.parameter_kind(spec.path), "/sweep/stop")
    values = sweep_values(first, last, spec.steps)
    return sweep(mech, spec.path, values, options, start, progress), target


def document_sweep(
    mech: Mechanism, options: NewtonOptions = NewtonOptions(), start: Start = "previous", progress=None
) -> tuple[SweepResult | None, TargetResult | None]:
    """Run the sweep declared in the document's `sweep` section (see run_sweep_spec)."""
    if mech.document.sweep is None:
        raise MechanismError("/sweep", "the document declares no sweep (give path, start and stop or until)")
    return run_sweep_spec(mech, mech.document.sweep, options, start, progress)


def _doc_value(mech: Mechanism, value, kind: str, pointer: str) -> float:
    """A document number (bare or with units) in the document's unit of `kind`."""
    return quantity_to_si(value, kind, mech.doc_unit(kind), pointer) / mech.doc_factor(kind)
