"""The configuration figure of an equilibrium: the undeformed and deformed mechanism, its
loads as arrows, and labels placed where they cover nothing else."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from flexmech.service.drawings.figures import check_plot_path, new_figure, save_figure, set_labels

if TYPE_CHECKING:  # matplotlib is imported when a figure is drawn, not with the package
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from flexmech.models import Mechanism
    from flexmech.service.solvers.equilibrium import EquilibriumResult

_UNDEFORMED = dict(color="0.65", linestyle="--", linewidth=1.0)
_FLEXURE = dict(color="C0", linewidth=1.8)
_BODY = dict(color="0.15", linewidth=2.6, solid_capstyle="round")
_LOAD = dict(color="C2", fontsize=9)
# A force arrow's length for the largest force, as a fraction of the drawing's span.
_ARROW_SPAN = 0.2
# Element labels are tried at these fractions of its samples, these distances (points) off it.
_LABEL_FRACTIONS = (0.5, 0.3, 0.7, 0.15, 0.85)
_LABEL_DISTANCES = (9.0, 16.0, 26.0)


def configuration_figure(result: EquilibriumResult) -> Figure:
    """The undeformed (dashed, light) and deformed (solid) mechanism of an equilibrium result.

    Flexures and links are drawn from their centre-line samples; bodies as skeletons joining
    their reference point to the element attachments and point outputs they carry; fixed bodies'
    reference points are squares, point outputs stars. A force load is an arrow ending at its
    point of application, deformed (the largest a fifth of the drawing's span), a moment a
    circular arrow at its body's reference point, each labelled with its name and value.
    Element labels go where they cover no other label. Document length unit, equal aspect.
    """
    mech = result.mechanism
    # 2 x samples of every element, document units
    deformed, undeformed = (
        np.asarray(a, dtype=float) / mech.nd_per_doc("length") for a in mech.graphs.shapes(result.z, mech.p())
    )
    outputs = result.outputs()
    fig = new_figure(7.0, 6.5)
    ax = fig.add_subplot()
    _draw_skeletons(ax, mech, outputs, deformed, undeformed)
    elements = _draw_elements(ax, mech.graphs.shape_segments, deformed, undeformed)
    labels = _draw_bodies_and_points(ax, mech, outputs)
    drawn = np.hstack([deformed, undeformed, _reference_points(mech, outputs)[0].T])
    loads = _draw_loads(ax, mech, outputs, float(np.ptp(drawn, axis=1).max()) if drawn.size else 1.0)
    ax.set_aspect("equal", adjustable="datalim")
    status = result.status if result.converged else f"{result.status} (last iterate, not an equilibrium)"
    title = f"{mech.document.name}\n{status}, {result.iterations} iterations"
    set_labels(
        ax, *(f"{c} [{mech.doc_unit('length')}]" for c in "xy"), title, legend=bool(ax.get_legend_handles_labels()[0])
    )  # a spring chain may have no labelled element
    _placeset_labels(fig, ax, loads + labels + elements)
    return fig


def plot_configuration(result: EquilibriumResult, path: str | Path) -> Path:
    """configuration_figure saved to `path` (.png or .svg). Returns the path written."""
    return save_figure(configuration_figure(result), check_plot_path(path))


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
    for refs, attached, style, label in (
        (ref_then, attached_then, _UNDEFORMED, "undeformed"),
        (ref_now, attached_now, _BODY, "deformed bodies"),
    ):
        for b in range(n_bodies):
            for q in attached[b]:
                ax.plot([refs[b, 0], q[0]], [refs[b, 1], q[1]], **style, label=label)
                label = None


def _draw_elements(ax, segments, deformed: np.ndarray, undeformed: np.ndarray) -> list:
    """The elements' centre lines; returns their labels: (name, places to try, best first, style)."""
    labels = []
    for k, (name, first, count, _, _) in enumerate(segments):
        columns = slice(first, first + count)
        ax.plot(undeformed[0, columns], undeformed[1, columns], **_UNDEFORMED)
        ax.plot(deformed[0, columns], deformed[1, columns], **_FLEXURE, label="deformed elements" if k == 0 else None)
        labels.append((name, _label_places(deformed[:, columns]), dict(color="C0", fontsize=9)))
    return labels


def _label_places(curve: np.ndarray) -> list[tuple[np.ndarray, tuple[float, float]]]:
    """Places for the label of a curve (2 x samples): points along it, offset along its normal
    away from its centroid (outward of an arc) at growing distances, then to the other side."""
    n = curve.shape[1]
    centroid = curve.mean(axis=1)
    places = []
    for fraction in _LABEL_FRACTIONS:
        i = min(n - 1, int(round(fraction * (n - 1))))
        normal = np.array([[0.0, -1.0], [1.0, 0.0]]) @ (curve[:, min(n - 1, i + 1)] - curve[:, max(0, i - 1)])
        length = float(np.hypot(*normal))
        normal = normal / length if length > 0 else np.array([0.0, 1.0])
        if np.dot(normal, curve[:, i] - centroid) < 0:
            normal = -normal
        for side in (1.0, -1.0):
            places += [(curve[:, i], tuple(side * d * normal)) for d in _LABEL_DISTANCES]
    return places


def _around(point: np.ndarray, text: str) -> list[tuple[np.ndarray, tuple[float, float]]]:
    """Places for a label beside a marker: right below, right above, left below, left above, ..."""
    w, h = 2.6 * len(text) + 6, 10.0
    return [(point, (sx * w, sy * h)) for sx, sy in ((1, -1), (1, 1), (-1, -1), (-1, 1), (0, -1.4), (0, 1.4))]


def _draw_bodies_and_points(ax, mech, outputs: dict) -> list:
    """Reference points and point outputs; returns their labels: (text, places, style)."""
    structure = mech.structure
    ref_now, ref_then = _reference_points(mech, outputs)
    fixed = [all(v is not None for v in row) for row in structure.prescribed]
    labels = []
    for b, name in enumerate(structure.bodies):
        marker = "s" if fixed[b] else "o"
        ax.plot(*ref_then[b], marker=marker, color="0.65", markerfacecolor="none", linestyle="none")
        ax.plot(*ref_now[b], marker=marker, color="0.15", linestyle="none")
        text = name + (" (fixed)" if fixed[b] else "")
        labels.append((text, _around(ref_now[b], text), dict(fontsize=9)))
    for i, point in enumerate(structure.points):
        now = np.array([outputs[f"{point.name}.x"], outputs[f"{point.name}.y"]])
        then = now - np.array([outputs[f"{point.name}.dx"], outputs[f"{point.name}.dy"]])
        ax.plot(*then, marker="*", markersize=10, color="0.65", markerfacecolor="none", linestyle="none")
        ax.plot(
            *now, marker="*", markersize=12, color="C3", linestyle="none", label="point outputs" if i == 0 else None
        )
        labels.append((point.name, _around(now, point.name), dict(color="C3", fontsize=9)))
    return labels


def load_point(mech: Mechanism, name: str, outputs: dict) -> np.ndarray:
    """Where the load `name` acts (a moment: its body's reference point) in the deformed
    configuration of the solution whose outputs (document units) are given: (x, y)."""
    load = next(t for t in mech.structure.loads if t.name == name)
    body = mech.structure.bodies[load.body]
    ref = np.array([outputs[f"bodies.{body}.x"], outputs[f"bodies.{body}.y"]])
    if load.location == "reference":
        return ref
    rad = mech.doc_factor("angle")  # points as complex numbers x + iy, turned by exp(i angle)
    local = complex(*(mech.value(f"/loads/{name}/{load.location}/{i}") for i in (0, 1)))
    if load.location == "at":  # a global undeformed point: into body axes
        origin = complex(*(mech.value(f"/bodies/{body}/position/{i}") for i in (0, 1)))
        local = (local - origin) * np.exp(-1j * mech.value(f"/bodies/{body}/angle") * rad)
    arm = local * np.exp(1j * outputs[f"bodies.{body}.angle"] * rad)
    return ref + np.array([arm.real, arm.imag])


def _draw_loads(ax, mech, outputs: dict, span: float) -> list:
    """Force loads as arrows ending at their point of application, moments as circular arrows
    at the reference point of their body; returns their labels: (text, places, style)."""
    loads = mech.structure.loads
    forces = {
        t.name: np.array([mech.value(f"/loads/{t.name}/force/{i}") for i in (0, 1)]) for t in loads if t.kind == "force"
    }
    largest = max((float(np.hypot(*f)) for f in forces.values()), default=0.0)
    labels = []
    for load in loads:
        if load.kind == "force":
            force = forces[load.name]
            size = float(np.hypot(*force))
            if size == 0.0:
                continue
            head = load_point(mech, load.name, outputs)
            tail = head - _ARROW_SPAN * span * force / largest
            ax.annotate(
                "",
                head,
                xytext=tail,
                arrowprops=dict(arrowstyle="-|>", color="C2", linewidth=1.8, mutation_scale=16, shrinkA=0, shrinkB=0),
            )
            ax.update_datalim(np.array([head, tail]))
            text = f"{load.name} {size:.4g} {mech.doc_unit('force')}"
            beyond = (tail, (-force[0] / size * (2.6 * len(text) + 4), -force[1] / size * 10))  # past the tail
            labels.append((text, [beyond, *_around(tail, text)], _LOAD))
        else:
            ref = load_point(mech, load.name, outputs)
            moment = mech.value(f"/loads/{load.name}/moment")
            ax.plot(
                *ref,
                marker=r"$\circlearrowleft$" if moment >= 0 else r"$\circlearrowright$",
                markersize=22,
                color="C2",
                linestyle="none",
            )
            text = f"{load.name} {moment:.4g} {mech.doc_unit('moment')}"
            labels.append((text, _around(ref, text)[1:], _LOAD))
    ax.autoscale_view()
    return labels


def _placeset_labels(fig: Figure, ax: Axes, labels: list) -> None:
    """Write each label (text, places, style), in turn, at the first of its places (a point
    and an offset in points to the text's centre) that lies inside the axes and covers no
    label written before, nor the legend, a line, a marker or an arrow; else at the place that
    does least harm (outside the axes worst, then over a label, then over the most lines)."""
    fig.canvas.draw()  # settle the layout and the limits, so that text extents are final
    ax.set(xlim=ax.get_xlim(), ylim=ax.get_ylim())
    renderer = fig.canvas.get_renderer()
    boxes = [ax.get_legend().get_window_extent(renderer)] if ax.get_legend() else []
    drawn = _drawn_paths(ax)
    for text, places, style in labels:
        note = ax.annotate(
            text, places[0][0], xytext=places[0][1], textcoords="offset points", ha="center", va="center", **style
        )
        best = None
        for point, offset in places:
            note.xy, note.xyann = point, offset
            box = note.get_window_extent(renderer).padded(2.0 * fig.dpi / 72)
            harm = (
                not (ax.bbox.contains(box.x0, box.y0) and ax.bbox.contains(box.x1, box.y1)),
                any(box.overlaps(other) for other in boxes),
                sum(path.intersects_bbox(box, filled=False) for path in drawn),
            )
            if best is None or harm < best[0]:
                best = (harm, point, offset, box)
            if harm == (False, False, 0):
                break
        note.xy, note.xyann = best[1], best[2]
        boxes.append(best[3])


def _drawn_paths(ax: Axes) -> list:
    """Every line, marker (a diagonal across it) and load arrow of the axes, display coordinates."""
    from matplotlib.path import Path as Polyline

    nothing = ("None", "none", "", " ", None)
    paths = [
        Polyline(ax.transData.transform([note.xyann, note.xy]))
        for note in ax.texts
        if getattr(note, "arrow_patch", None) is not None
    ]
    for line in ax.lines:
        xy, half = ax.transData.transform(line.get_xydata()), line.get_markersize() * ax.figure.dpi / 144
        if line.get_linestyle() not in nothing:
            paths.append(Polyline(xy))
        if line.get_marker() not in nothing:
            paths += [Polyline([q - half, q + half]) for q in xy]
    return paths
