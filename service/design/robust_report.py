"""What an optimum's robust objective and constraints are made of (service.design.robust), for
the optimize report: per robust output its nominal value, sigma and mean -+ k sigma, per yield
the first-order share and each spec's part, all in document units, from the first order at the
optimum's (polished) states."""

from __future__ import annotations

import numpy as np

from flexmech.service.design.problem import DesignProblem, OutputRef
from flexmech.service.design.robust import first_order, log_share, spread
from flexmech.service.design.states import case_params


def robust_report(problem: DesignProblem, x: np.ndarray) -> list[dict]:
    """One entry per robust objective or constraint (`of`: objective, constraints/<k>) at the
    NLP unknowns x; empty when the problem has none."""
    named = [("objective", problem.objective)]
    named += [("constraints/" + c.pointer.rsplit("/", 1)[1], c.output) for c in problem.constraints]
    named = [(of, ref) for of, ref in named if ref.robust is not None]
    if not named:
        return []
    mech, x = problem.mechanism, np.asarray(x, dtype=float)
    n_design, n_state = len(problem.slots), mech.structure.n_unknowns
    zs = np.split(x[n_design : n_design + n_state * len(problem.case_p)], len(problem.case_p))
    ps = case_params(problem, x[:n_design] * problem.scale)
    firsts: dict = {}
    entries: dict[str, dict] = {}
    for of, ref in named:
        key = (ref.case, ref.robust.scatter)
        if key not in firsts:
            firsts[key] = first_order(mech.structure, ref.robust, zs[ref.case], ps[ref.case])
        y, moves = firsts[key]
        if ref.source == "yield":
            entries[of] = _yield_entry(problem, ref, y, moves)
        elif of not in entries:  # a two-sided constraint is one entry
            entries[of] = _sigma_entry(problem, ref, y, moves)
    return [{"of": of, **entry} for of, entry in entries.items()]


def yield_bound(constraint, multiplier: float) -> float:
    """The yield at a yield constraint's active bound (1 for any other constraint): the NLP bounds
    ln(yield), so its multiplier per unit of the yield itself is the NLP's over this."""
    if constraint.output.source != "yield":
        return 1.0
    bound = constraint.upper if multiplier > 0 else constraint.lower
    return float(np.exp(bound)) if np.isfinite(bound) else 1.0


def _sigma_entry(problem: DesignProblem, ref: OutputRef, y: np.ndarray, moves: np.ndarray) -> dict:
    mech = problem.mechanism
    per = 1.0 / mech.nd_per_doc(ref.kind)
    nominal, sigma = y[ref.index] * per, float(spread(moves[ref.index, :])) * per
    k = abs(ref.sigmas)
    return {
        "output": ref.name,
        "case": problem.case_names[ref.case],
        "unit": mech.doc_unit(ref.kind),
        "sigmas": k,
        "nominal": float(nominal),
        "sigma": sigma,
        "mean_minus_k_sigma": float(nominal - k * sigma),
        "mean_plus_k_sigma": float(nominal + k * sigma),
    }


def _yield_entry(problem: DesignProblem, ref: OutputRef, y: np.ndarray, moves: np.ndarray) -> dict:
    """The first-order yield (the product of the specs' shares: independent specs) and each
    spec's nominal value, sigma, bounds and share."""
    mech = problem.mechanism
    names, kinds = mech.graphs.output_names, mech.graphs.output_kinds
    specs, total = {}, 1.0
    for index, low, high in ref.robust.specs:
        per = 1.0 / mech.nd_per_doc(kinds[index])
        sigma = float(spread(moves[index, :]))
        share = float(np.exp(float(log_share(y[index], sigma, low, high))))
        total *= share
        specs[names[index]] = {
            "unit": mech.doc_unit(kinds[index]),
            "nominal": float(y[index] * per),
            "sigma": sigma * per,
            "min": float(low * per) if np.isfinite(low) else None,
            "max": float(high * per) if np.isfinite(high) else None,
            "share": share,
        }
    return {"output": "yield", "case": problem.case_names[ref.case], "yield": total, "specs": specs}
