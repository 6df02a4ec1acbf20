"""Figures of solved mechanisms: a configuration plot, Fig. 9-style sweep curves and a
continuation path.

Each figure is built by a *_figure function, which returns the matplotlib Figure (so that it
can be inspected), and written by its plot_* counterpart. Figures are built on
matplotlib.figure.Figure with the Agg canvas, never through pyplot, so nothing global is
touched and nothing is left open. The format follows the file suffix (PLOT_SUFFIXES). All
numbers are drawn in the document's units and labelled with them.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from flexmech.service.display import on_axis
from flexmech.service.drawings.configuration_plot import configuration_figure, load_point, plot_configuration
from flexmech.service.drawings.figures import (
    PLOT_SUFFIXES,
    check_plot_path,
    field_label,
    new_figure,
    output_unit,
    save_figure,
    set_labels,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from flexmech.models import Mechanism
    from flexmech.service.solvers.continuation import PathResult
    from flexmech.service.solvers.sweep import SweepResult

__all__ = [
    "PLOT_SUFFIXES",
    "check_plot_path",
    "configuration_figure",
    "field_label",
    "load_point",
    "output_unit",
    "plot_configuration",
    "plot_sweeps",
    "plot_trace",
    "sweeps_figure",
    "trace_figure",
]


def sweeps_figure(
    curves: list[tuple[str, SweepResult]], x_output: str, y_output: str, field_path: str, secant: bool = False
) -> Figure:
    """Two panels in the manner of Fig. 9 of the paper, a line per curve sweeping `field_path`.
    Left, y_output against x_output (a point's trajectory when they are its x and y). Right,
    the swept field against x_output, or with `secant` (the field a prescribed displacement,
    y_output its reaction) the change of y_output over the field's from the first point.
    Unconverged points are left out; the last converged one is marked. Titles use the labels'
    words."""
    if not curves:
        raise ValueError("sweeps_figure: no curves to plot")
    for label, result in curves:
        if result.path != field_path or not {x_output, y_output} <= set(result.outputs):
            raise ValueError(
                f"sweeps_figure: curve '{label}' sweeps {result.path}, not {field_path}, "
                f"or lacks {x_output} or {y_output}"
            )
    mech = curves[0][1].mechanism
    field_unit = mech.doc_unit(mech.parameter_kind(field_path))
    right_name, right_unit = (
        (f"secant stiffness {y_output} / {field_label(field_path)}", f"{output_unit(mech, y_output)}/{field_unit}")
        if secant
        else (field_label(field_path), field_unit)
    )

    fig = new_figure(11.0, 4.6)
    left, right = fig.subplots(1, 2)
    drawn = [_curve(label, result, x_output, y_output, secant) for label, result in curves]
    # each axis in its display unit (service.display), as the tables show the same numbers
    x_unit, xs = on_axis(output_unit(mech, x_output), [d[2] for d in drawn])
    y_unit, ys = on_axis(output_unit(mech, y_output), [d[3] for d in drawn])
    right_unit, rights = on_axis(right_unit, [d[4] for d in drawn])
    for (label, ok, _, _, _), x, y, values in zip(drawn, xs, ys, rights):
        (line,) = left.plot(x, y, label=label)
        right.plot(x, values, label=label, color=line.get_color())
        if ok.any():  # the end of the path, e.g. the closed gripper
            last = np.flatnonzero(ok)[-1]
            left.plot(x[last], y[last], "o", color=line.get_color(), markersize=4)
            right.plot(x[last], values[last], "o", color=line.get_color(), markersize=4)

    point, _, component = x_output.rpartition(".")
    trajectory = component == "x" and y_output == f"{point}.y"
    set_labels(
        left,
        f"{x_output} [{x_unit}]",
        f"{y_output} [{y_unit}]",
        f"trajectory of {point}" if trajectory else f"{y_output} against {x_output}",
    )
    set_labels(
        right,
        f"{x_output} [{x_unit}]",
        f"{right_name} [{right_unit}]",
        f"{right_name} against {x_output}",
    )
    fig.suptitle(mech.document.name, fontsize=11)
    return fig


def _curve(label: str, result: SweepResult, x_output: str, y_output: str, secant: bool) -> tuple:
    """(label, converged, x, y, right-hand values) of one sweep, NaN where it did not converge."""
    ok = np.array([s == "converged" for s in result.status])
    x = np.where(ok, result.outputs[x_output], np.nan)
    y = np.where(ok, result.outputs[y_output], np.nan)
    values = np.where(ok, result.values, np.nan)
    if secant:
        with np.errstate(divide="ignore", invalid="ignore"):
            values = np.where(values != values[0], (y - y[0]) / (values - values[0]), np.nan)
    return label, ok, x, y, values


def plot_sweeps(
    curves: list[tuple[str, SweepResult]],
    x_output: str,
    y_output: str,
    field_path: str,
    path: str | Path,
    secant: bool = False,
) -> Path:
    """sweeps_figure saved to `path` (.png or .svg). Returns the path written."""
    return save_figure(sweeps_figure(curves, x_output, y_output, field_path, secant), check_plot_path(path))


def trace_figure(mech: Mechanism, result: PathResult, output: str) -> Figure:
    """The followed field (vertical) against `output` (horizontal) along a continuation path:
    stretches between stable points solid, the others (unstable, or singular) dashed, with the
    stability changing at the limit points, which are marked and labelled with their value."""
    if output not in mech.graphs.output_names:
        raise ValueError(f"trace_figure: no output '{output}'")
    # (output, field, stable) in path order; a limit point (stable None) goes where it lies
    rows = [(p.outputs[output], p.value, p.stability.stable is True) for p in result.points]
    for lp in sorted(result.limit_points, key=lambda lp: lp.after_point, reverse=True):
        rows.insert(lp.after_point + 1, (lp.outputs[output], lp.value, None))
    # each stretch is as stable as its first end, or as its second where the first is a limit point
    flags = [rows[k][2] if rows[k][2] is not None else rows[k + 1][2] is True for k in range(len(rows) - 1)]
    edges = [k for k in range(len(flags)) if k == 0 or flags[k] != flags[k - 1]] + [len(flags)]
    xy = np.array([row[:2] for row in rows], dtype=float)
    fig = new_figure(7.0, 5.0)
    ax = fig.add_subplot()
    named = set()
    for a, b in zip(edges, edges[1:]):
        name = "stable" if flags[a] else "unstable"
        ax.plot(
            xy[a : b + 1, 0],
            xy[a : b + 1, 1],
            "-" if flags[a] else "--",
            color="C0",
            label=None if name in named else name,
        )
        named.add(name)
    for k, lp in enumerate(result.limit_points):
        ax.plot(lp.outputs[output], lp.value, "o", color="C3", markersize=6, label="limit points" if k == 0 else None)
        side = -1 if lp.outputs[output] > np.mean(ax.get_xlim()) else 1  # write towards the middle
        ax.annotate(
            f"{lp.kind} {lp.value:.6g} {result.unit}",
            (lp.outputs[output], lp.value),
            color="C3",
            fontsize=9,
            xytext=(8 * side, 6 if lp.kind == "maximum" else -12),
            textcoords="offset points",
            ha="left" if side > 0 else "right",
        )
    set_labels(
        ax,
        f"{output} [{output_unit(mech, output)}]",
        f"{field_label(result.path)} [{result.unit}]",
        f"{mech.document.name}\n{field_label(result.path)} against {output}: {result.status}",
        legend=bool(named),
    )
    return fig


def plot_trace(mech: Mechanism, result: PathResult, output: str, path: str | Path) -> Path:
    """trace_figure saved to `path` (.png or .svg). Returns the path written."""
    return save_figure(trace_figure(mech, result, output), check_plot_path(path))
