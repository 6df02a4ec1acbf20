"""The example path of an export, and the iteration counts its manifest states: the Python
twin of the C iteration (service.export.kernels.iterate) run over the path, warm (each point
from the previous) and cold (each from the undeformed state)."""

from __future__ import annotations

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.service.export.kernels import ExportFunctions, iterate
from flexmech.service.export.plan import ExportPlan
from flexmech.service.export.sources import ExamplePath


def parameters_at(mech: Mechanism, plan: ExportPlan, values) -> np.ndarray:
    """The nondimensional p with the inputs set to values (document units)."""
    p = mech.p()
    for item, value in zip(plan.inputs, values):
        p[item.slot] = value * item.nd_per_unit
    return p


def defaults(plan: ExportPlan) -> np.ndarray:
    return np.array([i.default for i in plan.inputs], dtype=float)


def _doc(mech: Mechanism, plan: ExportPlan, index: int, value, pointer: str) -> float:
    item = plan.inputs[index]
    return mech.checked_si(item.pointer, value, pointer, own_checks=False) / mech.doc_factor(item.kind)


def _contact_path(mech: Mechanism, plan: ExportPlan) -> ExamplePath | None:
    from flexmech.service.contact.path import path_fields

    spec = mech.document.contacts.path if mech.document.contacts is not None else None
    if spec is None or not spec.parameters:
        return None
    fields = path_fields(mech, spec.parameters, "/contacts/path/parameters")
    pointers = [i.pointer for i in plan.inputs]
    if not all(p in pointers for p in fields.pointers):
        return None
    indices = tuple(pointers.index(p) for p in fields.pointers)
    firsts = tuple(v[0] for v in fields.values)
    lasts = tuple(v[-1] for v in fields.values)
    return ExamplePath(indices, firsts, lasts, fields.states, "contact")


def example_path(mech: Mechanism, plan: ExportPlan, functions: ExportFunctions) -> ExamplePath:
    """The path of _example_path, checked against the inputs' ranges (the example, benchmark
    and checks run it)."""
    path = _example_path(mech, plan, functions)
    for k, a, b in zip(path.indices, path.starts, path.stops):
        item = plan.inputs[k]
        low, high = min(a, b), max(a, b)
        if low < item.low or high > item.high or (item.low_excluded and low == item.low):
            raise MechanismError(
                f"/ranges/{item.pointer}",
                f"the example path takes {item.c_name} from {a:.10g} to {b:.10g} {item.unit}, outside its range "
                f"[{item.low:g}, {item.high:g}]: widen it",
            )
    return path


def _example_path(mech: Mechanism, plan: ExportPlan, functions: ExportFunctions) -> ExamplePath:
    """A contact document's contact path (when its fields are inputs); else the document's
    sweep when it moves an input (to the target when it has one); else the inputs the document
    sets to a value other than zero, ramped together from zero to it (its loads applied)."""
    if functions.contact is not None:
        found = _contact_path(mech, plan)
        if found is not None:
            return found
    spec = mech.document.sweep
    pointers = [i.pointer for i in plan.inputs]
    if spec is not None and spec.path in pointers:
        k = pointers.index(spec.path)
        start = _doc(mech, plan, k, spec.start, "/sweep/start")
        if plan.target is not None and plan.target.input == k:
            found = target_iterations(mech, plan, functions, defaults(plan), plan.target.default_goal)
            if found is not None:
                return ExamplePath((k,), (start,), (found[0],))
        if spec.stop is not None:
            return ExamplePath((k,), (start,), (_doc(mech, plan, k, spec.stop, "/sweep/stop"),))
    loaded = tuple(k for k, item in enumerate(plan.inputs) if item.default != 0)
    if not loaded:  # nothing to ramp: the document's state, held
        return ExamplePath((0,), (0.0,), (0.0,))
    return ExamplePath(loaded, tuple(0.0 for _ in loaded), tuple(plan.inputs[k].default for k in loaded))


def target_iterations(mech, plan: ExportPlan, functions: ExportFunctions, inputs, goal: float):
    """The target task as the C library runs it from a cold start: (the solved input in
    document units, Newton steps), or None when it does not converge."""
    p = parameters_at(mech, plan, inputs)
    first = iterate(functions.eq_step, np.zeros(mech.n_free), (p,), plan)
    if first.status != 0:
        return None
    k = plan.target.input
    x0 = np.concatenate([first.x, [p[plan.inputs[k].slot]]])
    found = iterate(functions.target_step, x0, (p, goal), plan)
    if found.status != 0:
        return None
    return found.x[-1] / plan.inputs[k].nd_per_unit, first.iterations + found.iterations


def contact_twin(contact, v: np.ndarray | None, p: np.ndarray, plan: ExportPlan):
    """The C contact task: from v (the last state), and from the cold start when that fails;
    (Iteration, steps in all)."""
    first = iterate(contact.step, v, (p,), plan) if v is not None else None
    if first is not None and first.status == 0:
        return first, first.iterations
    again = iterate(contact.step, np.asarray(contact.start(p), dtype=float).ravel(), (p,), plan)
    return again, again.iterations + (first.iterations if first is not None else 0)


def _over_path(solve, mech, plan: ExportPlan, path: ExamplePath) -> tuple[int, int, int]:
    """(worst warm steps, worst cold steps, failed points) of one task's twin over the path;
    solve(previous or None, p) -> (Iteration, steps)."""
    warm, cold, failed = 0, 0, 0
    x = None
    for values in path.values(defaults(plan)):
        p = parameters_at(mech, plan, values)
        (a, a_steps), (b, b_steps) = solve(x, p), solve(None, p)
        failed += int(a.status != 0) + int(b.status != 0)
        x = a.x if a.status == 0 else x
        warm, cold = max(warm, a_steps), max(cold, b_steps)
    return warm, cold, failed


def worst_iterations(mech: Mechanism, plan: ExportPlan, functions: ExportFunctions, path: ExamplePath) -> dict:
    """Newton steps of the twin over the example path, per task, warm and cold; and the
    target's cold start."""
    moved = ", ".join(
        f"{plan.inputs[k].c_name} from {a:.10g} to {b:.10g} {plan.inputs[k].unit}"
        for k, a, b in zip(path.indices, path.starts, path.stops)
    )
    out: dict = {"measured_over": f"{path.points} points: {moved}"}

    def equilibrium(z, p):
        found = iterate(functions.eq_step, np.zeros(mech.n_free) if z is None else z, (p,), plan)
        return found, found.iterations

    warm, cold, failed = _over_path(equilibrium, mech, plan, path)
    out.update(equilibrium_warm=warm, equilibrium_cold=cold, failed_points=failed)
    if functions.contact is not None:
        warm, cold, failed = _over_path(lambda v, p: contact_twin(functions.contact, v, p, plan), mech, plan, path)
        out.update(contact_warm=warm, contact_cold=cold, contact_failed_points=failed)
    if plan.target is not None:
        found = target_iterations(mech, plan, functions, defaults(plan), plan.target.default_goal)
        out["target_cold"] = None if found is None else int(found[1])
    failed = out["failed_points"] + out.get("contact_failed_points", 0)
    if failed:
        raise MechanismError(
            "/inputs",
            f"the exported iteration (at most {plan.options.max_iterations} steps, warm or from undeformed) fails "
            f"{failed} times over its example path ({out['measured_over']}): the library would not solve its own "
            "example; choose inputs it converges along, or a document sweep without limit points",
        )
    return out
