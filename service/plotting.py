"""Figures of solved mechanisms: a configuration plot and Fig. 9-style sweep curves.

Figures are built on matplotlib.figure.Figure with the Agg canvas, never through pyplot, so
nothing global is touched and nothing is left open. The format follows the file suffix
(PLOT_SUFFIXES). All numbers are drawn in the document's units and labelled with them.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np


if TYPE_CHECKING:  # matplotlib is imported when a figure is drawn, not with the package
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from models import Mechanism
    from service.equilibrium import EquilibriumResult
    from service.sweep import SweepResult

PLOT_SUFFIXES = (".png", ".svg")

_UNDEFORMED = dict(color="0.65", linestyle="--", linewidth=1.0)
_FLEXURE = dict(color="C0", linewidth=1.8)
_BODY = dict(color="0.15", linewidth=2.6, solid_capstyle="round")


def check_plot_path(path: str | Path) -> Path:
    """The path as a Path; ValueError unless its suffix is one of PLOT_SUFFIXES."""
    path = Path(path)
    if path.suffix.lower() not in PLOT_SUFFIXES:
        raise ValueError(f"cannot tell the figure format of '{path}': use a name ending in "
                         f"{' or '.join(PLOT_SUFFIXES)}")
    return path


def field_label(pointer: str) -> str:
    """A short reading of a numeric field's JSON pointer for axis labels:
    /loads/actuation/force/1 -> "actuation force y", /sections/flexure/h -> "flexure h"."""
    parts = [p for p in pointer.split("/") if p]
    if len(parts) >= 2 and parts[-1] in ("0", "1") and parts[-2] in ("force", "position", "center",
                                                                    "at", "offset"):
        parts[-1] = "xy"[int(parts[-1])]
    if len(parts) >= 3:
        parts = parts[1:]  # drop the collection: the name already says what it is
    return " ".join(parts) if parts else pointer


def output_unit(mech: "Mechanism", name: str) -> str:
    """Document unit of the output `name`; KeyError if the mechanism has no such output."""
    names = mech.graphs.output_names
    if name not in names:
        raise KeyError(name)
    return mech.doc_unit(mech.graphs.output_kinds[names.index(name)])


def _new_figure(width: float, height: float) -> "Figure":
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _save(fig: "Figure", path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, format=path.suffix.lower().lstrip("."), dpi=150)


def plot_configuration(result: "EquilibriumResult", path: str | Path) -> Path:
    """Draw the undeformed (dashed, light) and deformed (solid) mechanism of an equilibrium
    result and save it to `path` (.png or .svg). Returns the path written.

    Flexures and links are drawn from their centre-line samples; bodies as skeletons joining
    their reference point to the element attachments and point outputs they carry; fixed bodies'
    reference points are squares, point outputs stars. Axes in the document's length unit,
    equal aspect.
    """
    path = check_plot_path(path)
    mech = result.mechanism
    to_doc = 1.0 / mech.nd_per_doc("length")
    deformed_nd, undeformed_nd = mech.graphs.shapes(result.z, mech.p())
    deformed = np.asarray(deformed_nd, dtype=float) * to_doc  # 2 x samples of every element
    undeformed = np.asarray(undeformed_nd, dtype=float) * to_doc
    outputs = result.outputs()
    fig = _new_figure(7.0, 6.5)
    ax = fig.add_subplot()
    _draw_skeletons(ax, mech, outputs, deformed, undeformed)
    _draw_elements(ax, mech.graphs.shape_segments, deformed, undeformed)
    _draw_bodies_and_points(ax, mech, outputs)
    unit = mech.doc_unit("length")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"x [{unit}]")
    ax.set_ylabel(f"y [{unit}]")
    ax.grid(True, linewidth=0.4, alpha=0.5)
    if ax.get_legend_handles_labels()[0]:  # a spring chain may have no labelled element
        ax.legend(loc="best", fontsize=8)
    status = result.status if result.converged else f"{result.status} (last iterate, not an equilibrium)"
    ax.set_title(f"{mech.document.name}\n{status}, {result.iterations} iterations", fontsize=10)
    _save(fig, path)
    return path


def _reference_points(mech, outputs: dict) -> tuple[np.ndarray, np.ndarray]:
    """Every body's reference point now and undeformed, document units."""
    bodies = mech.structure.bodies
    now = np.array([[outputs[f"bodies.{b}.x"], outputs[f"bodies.{b}.y"]] for b in bodies])
    then = np.array([[mech.value(f"/bodies/{b}/position/0"), mech.value(f"/bodies/{b}/position/1")] for b in bodies])
    return now, then


def _draw_skeletons(ax, mech, outputs: dict, deformed: np.ndarray, undeformed: np.ndarray) -> None:
    """Body skeletons: reference point -> attachments and point outputs on the body."""
    structure = mech.structure
    n_bodies = len(structure.bodies)
    ref_now, ref_then = _reference_points(mech, outputs)
    attached_now: list[list[np.ndarray]] = [[] for _ in range(n_bodies)]
    attached_then: list[list[np.ndarray]] = [[] for _ in range(n_bodies)]
    for _, first, count, start_body, end_body in mech.graphs.shape_segments:
        last = first + count - 1
        for body, column in ((start_body, first), (end_body, last)):
            attached_now[body].append(deformed[:, column])
            attached_then[body].append(undeformed[:, column])
    for point in structure.points:
        now = np.array([outputs[f"{point.name}.x"], outputs[f"{point.name}.y"]])
        attached_now[point.body].append(now)
        attached_then[point.body].append(now - np.array([outputs[f"{point.name}.dx"], outputs[f"{point.name}.dy"]]))
    for refs, attached, style, label in ((ref_then, attached_then, _UNDEFORMED, "undeformed"),
                                         (ref_now, attached_now, _BODY, "deformed bodies")):
        for b in range(n_bodies):
            for q in attached[b]:
                ax.plot([refs[b, 0], q[0]], [refs[b, 1], q[1]], **style, label=label)
                label = None


def _draw_elements(ax, segments, deformed: np.ndarray, undeformed: np.ndarray) -> None:
    for k, (name, first, count, _, _) in enumerate(segments):
        columns = slice(first, first + count)
        ax.plot(undeformed[0, columns], undeformed[1, columns], **_UNDEFORMED)
        ax.plot(deformed[0, columns], deformed[1, columns], **_FLEXURE,
                label="deformed elements" if k == 0 else None)
        middle = deformed[:, first + count // 2]
        outward = middle - deformed[:, columns].mean(axis=1)  # away from a curve's centre
        norm = float(np.hypot(*outward))
        outward = 9 * outward / norm if norm > 1e-12 * max(np.abs(deformed).max(), 1e-300) else np.array([0.0, 9.0])
        ax.annotate(name, middle, color="C0", fontsize=9, ha="center",
                    va="center", xytext=tuple(outward), textcoords="offset points")


def _draw_bodies_and_points(ax, mech, outputs: dict) -> None:
    structure = mech.structure
    ref_now, ref_then = _reference_points(mech, outputs)
    fixed = [all(v is not None for v in row) for row in structure.prescribed]
    for b, name in enumerate(structure.bodies):
        marker = "s" if fixed[b] else "o"
        ax.plot(*ref_then[b], marker=marker, color="0.65", markerfacecolor="none", linestyle="none")
        ax.plot(*ref_now[b], marker=marker, color="0.15", linestyle="none")
        ax.annotate(name + (" (fixed)" if fixed[b] else ""), ref_now[b], fontsize=9,
                    xytext=(5, -11), textcoords="offset points")
    for i, point in enumerate(structure.points):
        now = np.array([outputs[f"{point.name}.x"], outputs[f"{point.name}.y"]])
        then = now - np.array([outputs[f"{point.name}.dx"], outputs[f"{point.name}.dy"]])
        ax.plot(*then, marker="*", markersize=10, color="0.65", markerfacecolor="none", linestyle="none")
        ax.plot(*now, marker="*", markersize=12, color="C3", linestyle="none",
                label="point outputs" if i == 0 else None)
        ax.annotate(point.name, now, color="C3", fontsize=9, xytext=(6, 4), textcoords="offset points")


def plot_sweeps(curves: "list[tuple[str, SweepResult]]", x_output: str, y_output: str,
                force_path: str, path: str | Path) -> Path:
    """Two panels in the manner of Fig. 9 of the paper, one labelled line per curve:
    left, the trajectory of a point (x_output against y_output); right, the swept field
    (each curve's SweepResult.values, which must sweep `force_path`) against x_output.
    Points that did not converge are left out of the lines. Saves to `path` (.png or .svg)
    and returns it.
    """
    path = check_plot_path(path)
    if not curves:
        raise ValueError("plot_sweeps: no curves to plot")
    for label, result in curves:
        if result.path != force_path:
            raise ValueError(f"plot_sweeps: curve '{label}' sweeps {result.path}, not {force_path}")
        for name in (x_output, y_output):
            if name not in result.outputs:
                raise ValueError(f"plot_sweeps: curve '{label}' has no output '{name}'")
    mech = curves[0][1].mechanism
    x_unit, y_unit = output_unit(mech, x_output), output_unit(mech, y_output)
    field_unit = mech.doc_unit(mech.parameter_kind(force_path))

    fig = _new_figure(11.0, 4.6)
    trajectory: Axes = fig.add_subplot(1, 2, 1)
    load: Axes = fig.add_subplot(1, 2, 2)
    for label, result in curves:
        ok = np.array([s == "converged" for s in result.status])
        x = np.where(ok, result.outputs[x_output], np.nan)
        y = np.where(ok, result.outputs[y_output], np.nan)
        values = np.where(ok, result.values, np.nan)
        line, = trajectory.plot(x, y, label=label)
        load.plot(x, values, label=label, color=line.get_color())
        if ok.any():  # the end of the path, e.g. the closed gripper
            last = np.flatnonzero(ok)[-1]
            trajectory.plot(x[last], y[last], "o", color=line.get_color(), markersize=4)
            load.plot(x[last], values[last], "o", color=line.get_color(), markersize=4)

    trajectory.set_xlabel(f"{x_output} [{x_unit}]")
    trajectory.set_ylabel(f"{y_output} [{y_unit}]")
    trajectory.set_title(f"trajectory of {x_output.rsplit('.', 1)[0]}", fontsize=10)
    load.set_xlabel(f"{x_output} [{x_unit}]")
    load.set_ylabel(f"{field_label(force_path)} [{field_unit}]")
    load.set_title(f"{force_path} against {x_output}", fontsize=10)
    for ax in (trajectory, load):
        ax.grid(True, linewidth=0.4, alpha=0.5)
        ax.legend(fontsize=8)
    fig.suptitle(mech.document.name, fontsize=11)
    _save(fig, path)
    return path
