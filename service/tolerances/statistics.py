"""The statistics of a tolerance analysis: first order (mean = nominal, standard deviation from
the exact derivatives, each source's share of the variance), Monte Carlo (mean, standard
deviation, their standard errors, percentiles), whether the two agree within the Monte Carlo's
statistical error, and the yield against the specs."""

from __future__ import annotations

import math

import numpy as np

from flexmech.service.tolerances.fields import Scatter
from flexmech.service.tolerances.responses import Responses

PERCENTILES = (0.135, 2.275, 50.0, 97.725, 99.865)  # the median and +-2, +-3 sigma of a normal
AGREEMENT = 3.0  # standard errors within which Monte Carlo agrees with first order
PROBE = 3.0  # a normal source is probed at +-3 sigma (a uniform one at its ends) for the curvature
NEAR_LINEAR = 0.1  # the largest second-order mean shift, in first-order standard deviations, called near linear
BINS = 30  # of each response's histogram
FAILING_SHOWN = 50  # failing samples listed with their fields


def first_order(responses: Responses, scatter: Scatter) -> list[dict]:
    """Per response: mean (the nominal value), standard deviation, and every source's
    contribution (its share of the variance and the response's move per standard deviation of
    the source), largest first."""
    per_source = responses.jacobian @ scatter.loadings()  # responses x sources
    out = []
    for r in range(len(responses.names)):
        moves = per_source[r]
        variance = float(moves @ moves)
        order = np.argsort(-np.abs(moves), kind="stable")
        contributions = [
            {
                "source": scatter.sources[s],
                "fields": [f.path for f in scatter.fields if f.source == s],
                "per_sigma": float(moves[s]),
                "share": float(moves[s] ** 2 / variance) if variance > 0 else 0.0,
            }
            for s in order
        ]
        out.append({"mean": float(responses.nominal[r]), "std": math.sqrt(variance), "contributions": contributions})
    return out


def monte_carlo(values: np.ndarray, nominal: float, first: dict, shift: float | None) -> dict:
    """Statistics of one response's solved samples (NaN: not solved), and whether they agree with
    first order within their statistical error: the mean within AGREEMENT standard errors of the
    nominal value, the standard deviation within AGREEMENT of its standard error (sqrt(2 (n - 1))
    under normality). `shift`, the second-order mean shift (curvature), explains a difference."""
    solved = values[np.isfinite(values)]
    n = len(solved)
    if n < 2:
        return {"samples": n}
    mean, std = float(solved.mean()), float(solved.std(ddof=1))
    mean_error, std_error = std / math.sqrt(n), std / math.sqrt(2.0 * (n - 1))
    moved = (mean - nominal) / mean_error if mean_error > 0 else 0.0
    spread = (std - first["std"]) / std_error if std_error > 0 else 0.0
    agrees = abs(moved) <= AGREEMENT and abs(spread) <= AGREEMENT
    said = f"mean {moved:+.1f} standard errors from the nominal value"
    if shift is not None and mean_error > 0:
        said += f" (curvature predicts {shift / mean_error:+.1f})"
    if first["std"] > 0:
        said += f", standard deviation {std / first['std']:.4f} of first order's ({spread:+.1f} standard errors)"
    verdict = "agrees with first order within its statistical error" if agrees else "differs from first order"
    counts, edges = np.histogram(solved, bins=BINS)
    return {
        "samples": n,
        "mean": mean,
        "std": std,
        "mean_error": mean_error,
        "std_error": std_error,
        "percentiles": {f"{q:g}": float(np.percentile(solved, q)) for q in PERCENTILES},
        "min": float(solved.min()),
        "max": float(solved.max()),
        "agrees_with_first_order": bool(agrees),
        "agreement": f"{verdict}: {said}",
        "histogram": {"edges": edges.tolist(), "counts": counts.tolist()},
    }


def probes(scatter: Scatter) -> np.ndarray:
    """(2 sources x fields) deviations: each source at +PROBE and -PROBE sigma (a uniform one at
    +-its half width), the other sources at zero."""
    out = []
    for s, kind in enumerate(scatter.source_kinds):
        reach = PROBE if kind == "normal" else 1.0
        for sign in (1.0, -1.0):
            out.append([sign * reach * f.width if f.source == s else 0.0 for f in scatter.fields])
    return np.array(out)


def curvature(probed: np.ndarray, nominal: np.ndarray, scatter: Scatter, first: list[dict]) -> list[dict]:
    """Per response, the second-order shift of its mean, sum over sources of y'' var / 2 (the
    second difference of the probes at +-reach over reach^2, times E[xi^2]: 1, or 1/3 for a
    uniform source), and whether it is below NEAR_LINEAR first-order standard deviations."""
    out = []
    for r in range(len(nominal)):
        shift = 0.0
        for s, kind in enumerate(scatter.source_kinds):
            reach, moment = (PROBE, 1.0) if kind == "normal" else (1.0, 1.0 / 3.0)
            second = probed[2 * s, r] + probed[2 * s + 1, r] - 2.0 * nominal[r]
            shift += 0.5 * moment * second / reach**2
        std = first[r]["std"]
        relative = abs(shift) / std if std > 0 else (0.0 if shift == 0 else np.inf)
        near = bool(np.isfinite(relative) and relative <= NEAR_LINEAR)
        said = f"second-order mean shift {shift:+.4g} = {relative:.3f} standard deviations"
        out.append(
            {
                "second_order_shift": float(shift) if np.isfinite(shift) else None,
                "near_linear": near,
                "verdict": ("near linear: " if near else "not linear: first order misses ")
                + said
                + ("" if np.isfinite(shift) else " (a probe did not solve)"),
            }
        )
    return out


def spec_pass(values: np.ndarray, specs: dict[int, tuple[float, float]]) -> np.ndarray:
    """(samples x specs) whether each sample meets each spec (an unsolved sample meets none)."""
    columns = []
    for r, (low, high) in specs.items():
        v = values[:, r]
        columns.append(np.isfinite(v) & (v >= low) & (v <= high))
    return np.array(columns).T if columns else np.ones((len(values), 0), dtype=bool)


def normal_share(mean: float, std: float, low: float, high: float) -> float:
    """P(low <= y <= high) for y normal(mean, std)."""
    if std <= 0:
        return float(low <= mean <= high)

    def cdf(x: float) -> float:
        return 0.5 * math.erfc(-(x - mean) / (std * math.sqrt(2.0))) if math.isfinite(x) else float(x > 0)

    return cdf(high) - cdf(low)


def yield_report(
    values: np.ndarray, linear: np.ndarray, field_values: np.ndarray, specs: dict[int, tuple[float, float]], scatter
) -> dict:
    """The share of samples meeting every spec (its binomial standard error), the same share of
    the first-order model on the same samples, and the failing samples with their fields'
    values (document units)."""
    passed = spec_pass(values, specs).all(axis=1)
    n = len(values)
    share = float(passed.mean()) if n else float("nan")
    failing = np.flatnonzero(~passed)
    return {
        "monte_carlo": share,
        "standard_error": math.sqrt(share * (1 - share) / n) if n else float("nan"),
        "first_order": float(spec_pass(linear, specs).all(axis=1).mean()) if n else float("nan"),
        "samples": n,
        "failing": len(failing),
        "failing_samples": [
            {"sample": int(i), "fields": {f.path: float(field_values[i, k]) for k, f in enumerate(scatter.fields)}}
            for i in failing[:FAILING_SHOWN]
        ],
    }
