"""The tolerance analysis' figure: per response a row of two panels, the Monte Carlo histogram
(with the first-order normal density, the nominal value and the spec's bounds) and the
contributions of the sources to its variance (a tornado chart: per source its move per standard
deviation, largest on top)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from flexmech.service.drawings.figures import new_figure, save_figure

MAX_ROWS = 8  # responses drawn (the report holds every one)


def tolerance_figure(report: dict[str, Any], path: Path) -> Path:
    names = list(report["responses"])[:MAX_ROWS]
    fig = new_figure(10.0, 2.6 * max(len(names), 1))
    axes = fig.subplots(max(len(names), 1), 2, squeeze=False)
    for row, name in zip(axes, names):
        entry = report["responses"][name]
        _histogram(row[0], name, entry)
        _tornado(row[1], name, entry)
    fig.suptitle(f"{report['name']}: tolerances, {report['samples']} samples (seed {report['seed']})")
    return save_figure(fig, path)


def _histogram(ax, name: str, entry: dict[str, Any]) -> None:
    unit, first = entry["unit"], entry["first_order"]
    sampled = entry.get("monte_carlo", {})
    histogram = sampled.get("histogram")
    if histogram is not None:
        edges, counts = np.array(histogram["edges"]), np.array(histogram["counts"])
        widths = np.diff(edges)
        density = counts / max(counts.sum(), 1) / widths
        ax.bar(edges[:-1], density, width=widths, align="edge", color="0.75", label="Monte Carlo")
    mean, std = first["mean"], first["std"]
    if std > 0:
        x = np.linspace(mean - 4 * std, mean + 4 * std, 200)
        ax.plot(x, np.exp(-0.5 * ((x - mean) / std) ** 2) / (std * math.sqrt(2 * math.pi)), "C0", label="first order")
    ax.axvline(entry["nominal"], color="k", linewidth=0.8, label="nominal")
    for bound in (entry.get("spec") or {}).values():
        if bound is not None:
            ax.axvline(bound, color="C3", linestyle="--", linewidth=1.0)
    ax.set_xlabel(f"{name} ({unit})" if unit else name)
    ax.set_ylabel("density")
    ax.legend(fontsize="small")


def _tornado(ax, name: str, entry: dict[str, Any]) -> None:
    contributions = entry["first_order"]["contributions"][:12][::-1]  # largest on top
    labels = [c["source"] + (f" (+{len(c['fields']) - 1})" if len(c["fields"]) > 1 else "") for c in contributions]
    moves = [c["per_sigma"] for c in contributions]
    ax.barh(range(len(moves)), moves, color=["C0" if m >= 0 else "C1" for m in moves])
    ax.set_yticks(range(len(moves)), labels, fontsize="small")
    ax.axvline(0.0, color="k", linewidth=0.8)
    reach = 1.35 * max((abs(m) for m in moves), default=1.0) or 1.0  # room for the shares' labels
    ax.set_xlim(-reach if min(moves, default=0.0) < 0 else 0.0, reach if max(moves, default=0.0) > 0 else 0.0)
    unit = entry["unit"]
    ax.set_xlabel(f"{name} per standard deviation ({unit})" if unit else f"{name} per standard deviation")
    for k, c in enumerate(contributions):
        ax.annotate(
            f" {100 * c['share']:.1f} % ",
            (moves[k], k),
            fontsize="x-small",
            va="center",
            ha="left" if moves[k] >= 0 else "right",
        )
