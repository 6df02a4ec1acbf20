"""The report of a tolerance analysis: the scatter, each response's first-order and Monte Carlo
statistics, and the yield against the document's specs (service.tolerances.statistics), in
document units."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.documents.tolerances import TolerancesSpec
from flexmech.models.units import quantity_to_si
from flexmech.service.tolerances.fields import Scatter
from flexmech.service.tolerances.responses import Responses
from flexmech.service.tolerances.statistics import (
    curvature,
    first_order,
    monte_carlo,
    normal_share,
    probes,
    yield_report,
)


def spec_bounds(mech: Mechanism, spec: TolerancesSpec, responses: Responses) -> dict[int, tuple[float, float]]:
    """Each spec's response (its index) and bounds in the response's document unit."""
    bounds = {}
    for key, limits in spec.specs.items():
        where = "/tolerances/specs/" + key.replace("~", "~0").replace("/", "~1")
        if key not in responses.names:
            raise MechanismError(
                where, f"unknown response '{key}' (this analysis' responses: {', '.join(responses.names)})"
            )
        r = responses.names.index(key)
        kind, unit = responses.kinds[r], responses.units[r]

        def value(given, name: str) -> float:
            if given is None:
                return -np.inf if name == "min" else np.inf
            return quantity_to_si(given, kind, unit, f"{where}/{name}") / mech.doc_factor(kind)

        low, high = value(limits.min, "min"), value(limits.max, "max")
        if low > high:
            raise MechanismError(f"{where}/min", f"min ({low:g} {unit}) is above max ({high:g} {unit})")
        bounds[r] = (low, high)
    return bounds


def tolerance_report(
    mech: Mechanism,
    scatter: Scatter,
    responses: Responses,
    specs: dict[int, tuple[float, float]],
    samples: int,
    seed: int,
    stop: Callable[[], bool],
) -> dict:
    """First order always; Monte Carlo of `samples` samples drawn from `seed` (fewer when
    stopped: the report says how many ran)."""
    first = first_order(responses, scatter)
    probed, _ = responses.evaluate(probes(scatter), lambda: False)
    linearity = curvature(probed, responses.nominal, scatter, first)
    deviations = scatter.deviations(scatter.draws(samples, seed))
    values, statuses = responses.evaluate(deviations, stop) if samples else (np.zeros((0, len(first))), [])
    ran = len(statuses)
    values, deviations = values[:ran], deviations[:ran]
    report = {
        "fields": [_field(mech, f) for f in scatter.fields],
        "sources": list(scatter.sources),
        "samples": ran,
        "seed": seed,
        "unsolved_samples": sum(status != "converged" for status in statuses),
        "responses": {},
    }
    for r, name in enumerate(responses.names):
        entry = {
            "unit": responses.units[r],
            "nominal": float(responses.nominal[r]),
            "first_order": first[r],
            "linearity": linearity[r],
        }
        if ran:
            shift = linearity[r]["second_order_shift"]
            entry["monte_carlo"] = monte_carlo(values[:, r], float(responses.nominal[r]), first[r], shift)
        if r in specs:
            low, high = specs[r]
            entry["spec"] = {"min": _finite(low), "max": _finite(high)}
            entry["spec_share_first_order"] = normal_share(first[r]["mean"], first[r]["std"], low, high)
        report["responses"][name] = entry
    if specs and ran:
        field_values = deviations + np.array([mech.value(f.path) for f in scatter.fields])[None, :]
        report["yield"] = yield_report(values, responses.linearized(deviations), field_values, specs, scatter)
    return report


def _field(mech: Mechanism, field) -> dict:
    return {
        "path": field.path,
        "value": mech.value(field.path),
        "distribution": field.distribution,
        "width": field.width,
        "std": field.std,
        "unit": field.unit,
        "source": field.source,
    }


def _finite(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None
