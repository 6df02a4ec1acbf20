"""The responses of a tolerance analysis of a contact state or of natural frequencies: first order
from their exact sensitivities (service.contact.sensitivity on the state's active set,
service.vibration.sensitivity), each sample solved again (a contact state from the nominal one,
IPOPT warm-started; modes about the sample's equilibrium)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.tolerances.fields import Scatter
from flexmech.service.tolerances.responses import Responses


def modes_responses(
    mech: Mechanism,
    scatter: Scatter,
    outputs: list[str] | None,
    count: int,
    run_modes: Callable[[Mechanism, dict], dict],
) -> Responses:
    """frequency.1 ... frequency.<count> (Hz) about the equilibrium under the document's loads;
    run_modes(mechanism, options) is the modes analysis' report (service.analyses.modes)."""
    every = [f"frequency.{k + 1}" for k in range(count)]
    names = every if outputs is None else outputs
    for k, name in enumerate(names):
        if name not in every:
            raise MechanismError(f"/outputs/{k}", f"unknown response '{name}' (with count {count}: {', '.join(every)})")
    rows = [every.index(name) for name in names]
    nominal = run_modes(mech, {"count": count, "shapes": False, "sensitivities": scatter.paths})
    if nominal["status"] != "converged":
        raise MechanismError("/document", f"the nominal design's modes: {nominal['status']}")
    found = [nominal["modes"][r] for r in rows]
    jacobian = np.array([[mode["sensitivities"][path] or np.nan for path in scatter.paths] for mode in found])

    def solve(sample: Mechanism) -> tuple[str, np.ndarray]:
        report = run_modes(sample, {"count": count, "shapes": False})
        frequencies = [report["modes"][r]["frequency"] if r < len(report["modes"]) else None for r in rows]
        return report["status"], np.array([np.nan if f is None else f for f in frequencies], dtype=float)

    nominal_values = np.array([mode["frequency"] for mode in found], dtype=float)
    evaluate = _by_mechanism(mech, scatter, solve, len(rows))
    return Responses(names, ["frequency"] * len(names), ["Hz"] * len(names), nominal_values, jacobian, evaluate)


def contact_responses(mech: Mechanism, scatter: Scatter, outputs: list[str] | None, newton: NewtonOptions) -> Responses:
    """A frictionless contact state's outputs (default: every pair's normal force, and the
    document's named outputs) under the document's loads."""
    from flexmech.service.contact.problem import contact_problem
    from flexmech.service.contact.sensitivity import contact_sensitivities
    from flexmech.service.contact.solve import ContactOptions, solve_state
    from flexmech.service.tolerances.statics import default_outputs

    problem = contact_problem(mech.structure)
    pairs = [f"contacts.{name}.normal_force" for name in mech.document.contacts.pairs] if mech.document.contacts else []
    names = [*pairs, *default_outputs(mech)] if outputs is None else outputs
    for k, name in enumerate(names):
        if name not in problem.output_names:
            raise MechanismError(f"/outputs/{k}", f"unknown contact output '{name}' (for example {', '.join(pairs)})")
    options = ContactOptions(time_limit=newton.time_limit)
    p0 = mech.p()
    mu = _frictionless(mech, problem)
    start = solve_state(problem, p0, mu, options=options)
    if not start.converged:
        raise MechanismError("/document", f"the nominal design's contact state: {start.status}")
    found, _ = contact_sensitivities(mech, problem, start, scatter.paths, names, "/tolerances")
    rows = [problem.output_names.index(name) for name in names]
    kinds = [problem.output_kinds[r] for r in rows]
    scale = np.array([mech.nd_per_doc(kind) for kind in kinds])

    def values(state) -> np.ndarray:
        mode = state.mode
        y = np.asarray(problem.outputs(state.v, state.p, mode.phi, mode.stick, mode.weights), dtype=float).ravel()
        return y[rows] / scale

    def evaluate(deviations: np.ndarray, stop: Callable[[], bool]) -> tuple[np.ndarray, list[str]]:
        out, statuses = np.full((len(deviations), len(rows)), np.nan), []
        nd = scatter.nondimensional(mech, deviations)
        for i, move in enumerate(nd):
            if stop():
                break
            p = p0.copy()
            p[scatter.slots] += move
            state = solve_state(problem, p, mu, previous=start, options=options)
            statuses.append(state.status)
            if state.converged:
                out[i] = values(state)
        return out, statuses

    units = [mech.doc_unit(kind) for kind in kinds]
    return Responses(list(names), kinds, units, values(start), found.matrix, evaluate)


def _frictionless(mech: Mechanism, problem) -> np.ndarray:
    from flexmech.service.contact.report import friction_coefficients

    return 0.0 * friction_coefficients(mech, problem)


def _by_mechanism(mech: Mechanism, scatter: Scatter, solve, width: int):
    """Samples evaluated on the mechanism with the fields' values changed (document units)."""
    nominal = np.array([mech.value(path) for path in scatter.paths])

    def evaluate(deviations: np.ndarray, stop: Callable[[], bool]) -> tuple[np.ndarray, list[str]]:
        out, statuses = np.full((len(deviations), width), np.nan), []
        for i, move in enumerate(deviations):
            if stop():
                break
            sample = mech.with_values(dict(zip(scatter.paths, (nominal + move).tolist())))
            status, out[i] = solve(sample)
            statuses.append(status)
        return out, statuses

    return evaluate
