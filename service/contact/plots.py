"""Figures of contact: chosen states of a path drawn over each other (links with their
surfaces, jaws, objects, contact forces as arrows; like Lan 2005 Figs. 6.5 and 6.7), and a
contact result against the path's field (force against object position, one curve per run)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from flexmech.service.drawings.figures import check_plot_path, new_figure, save_figure, set_labels

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from flexmech.models import Mechanism
    from flexmech.service.contact.problem import ContactProblem
    from flexmech.service.contact.solve import ContactState

ARROW_SPAN = 0.15  # the largest force's arrow, as a fraction of the drawing's span
IMPLICIT_GRID = 201


def states_figure(mech: Mechanism, problem: ContactProblem, states: list[ContactState], labels: list[str]) -> Figure:
    from flexmech.service.contact.kkt import split
    from flexmech.service.contact.report import pair_values

    fig = new_figure(7.5, 6.0)
    ax = fig.add_subplot()
    to_doc = 1.0 / mech.nd_per_doc("length")
    drawn = []
    for state in states:
        w = split(problem, state.v).w
        jaws, links = (np.asarray(a, dtype=float) * to_doc for a in problem.drawing(w, state.p))
        drawn.append((w, jaws, links, pair_values(problem, state)))
    everything = np.hstack([np.hstack([jaws, links]) for _, jaws, links, _ in drawn] + [np.zeros((2, 1))])
    span = max(float(np.ptp(everything, axis=1).max()), 1e-12)
    centre = everything.mean(axis=1)
    largest = max((float(np.abs(v["normal_force"]).max(initial=0.0)) for *_, v in drawn), default=0.0)
    for k, (state, label, (w, jaws, links, pairs)) in enumerate(zip(states, labels, drawn)):
        color = f"C{k % 10}"
        _draw_links(ax, problem, links, color, label)
        _draw_jaws(ax, problem, jaws, color)
        _draw_objects(ax, mech, problem, w, state.p, color, centre, span)
        _draw_forces(ax, pairs, state, largest, color, to_doc, span)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlim(everything[0].min() - 0.3 * span, everything[0].max() + 0.3 * span)
    ax.set_ylim(everything[1].min() - 0.3 * span, everything[1].max() + 0.3 * span)
    unit = mech.doc_unit("length")
    set_labels(ax, f"x [{unit}]", f"y [{unit}]", f"{mech.document.name}: contact states")
    return fig


def _draw_links(ax, problem, links: np.ndarray, color: str, label: str) -> None:
    start = 0
    for k, (_, count) in enumerate(problem.drawn_links):
        block = links[:, start : start + 3 * count]
        start += 3 * count
        centre, left, right = block[:, 0::3], block[:, 1::3], block[:, 2::3]
        ax.plot(*centre, color=color, linewidth=0.8, linestyle=":")
        ax.plot(*left, color=color, linewidth=1.4, label=label if k == 0 else None)
        ax.plot(*right, color=color, linewidth=1.4)
        ax.plot([left[0, -1], right[0, -1]], [left[1, -1], right[1, -1]], color=color, linewidth=1.4)


def _draw_jaws(ax, problem, jaws: np.ndarray, color: str) -> None:
    start = 0
    for _, count, closed in problem.drawn_jaws:
        block = jaws[:, start : start + count]
        start += count
        if closed:
            block = np.hstack([block, block[:, :1]])
        ax.plot(*block, color=color, linewidth=1.6)


def _draw_objects(ax, mech, problem, w, p, color: str, centre: np.ndarray, span: float) -> None:
    from matplotlib.patches import Circle, Ellipse, Polygon

    to_doc = 1.0 / mech.nd_per_doc("length")
    origins, angles = (np.asarray(a, dtype=float) for a in problem.frames(w, p))
    angles = angles.ravel()
    style = dict(facecolor=color, alpha=0.12, edgecolor=color, linewidth=1.0)
    for k, obj in enumerate(problem.structure.contacts.objects):
        origin = origins[:, k] * to_doc

        def value(field: str) -> float:
            return p[mech.parameter_index(f"{obj.pointer}/{field}")] * to_doc

        if obj.type == "circle":
            ax.add_patch(Circle(origin, value("radius"), **style))
        elif obj.type == "hole":
            ax.add_patch(Circle(origin, value("radius"), fill=False, edgecolor=color, linewidth=1.0))
        elif obj.type == "ellipse":
            ax.add_patch(
                Ellipse(
                    origin, 2 * value("semi_axes/0"), 2 * value("semi_axes/1"), angle=np.degrees(angles[k]), **style
                )
            )
        elif obj.type == "polygon":
            count = 1 + max(max(piece) for piece in obj.pieces)
            local = np.array([[value(f"vertices/{i}/0"), value(f"vertices/{i}/1")] for i in range(count)])
            c, s = np.cos(angles[k]), np.sin(angles[k])
            ax.add_patch(Polygon(origin + local @ np.array([[c, s], [-s, c]]), closed=True, **style))
        elif obj.type == "half_plane":
            _draw_half_plane(ax, mech, obj, p, origin, angles[k], color, span)
        else:
            _draw_implicit(ax, obj, origin, angles[k], color, centre, span)


def _draw_half_plane(ax, mech, obj, p, origin, angle, color, span: float) -> None:
    normal = np.array([p[mech.parameter_index(f"{obj.pointer}/normal/{i}")] for i in range(2)])
    c, s = np.cos(angle), np.sin(angle)
    normal = np.array([[c, -s], [s, c]]) @ normal
    normal /= np.linalg.norm(normal)
    along = np.array([-normal[1], normal[0]])
    reach = 3 * span
    ends = np.array([origin - reach * along, origin + reach * along])
    ax.plot(*ends.T, color=color, linewidth=1.2)
    ax.fill(
        [*ends[:, 0], *(ends[::-1, 0] - reach * normal[0])],
        [*ends[:, 1], *(ends[::-1, 1] - reach * normal[1])],
        color=color,
        alpha=0.08,
    )


def _draw_implicit(ax, obj, origin, angle, color, centre: np.ndarray, span: float) -> None:
    """The region g < 0 around the drawing (g in the object's frame, document units)."""
    import casadi as ca

    from flexmech.models.documents.expression import compile_expression

    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    g = ca.Function("g", [x, y], [ca.SX(compile_expression(obj.expression, "", "x", ("y",))(x, {"y": y}))])
    grid_x = np.linspace(centre[0] - 1.5 * span, centre[0] + 1.5 * span, IMPLICIT_GRID)
    grid_y = np.linspace(centre[1] - 1.5 * span, centre[1] + 1.5 * span, IMPLICIT_GRID)
    X, Y = np.meshgrid(grid_x, grid_y)
    c, s = np.cos(angle), np.sin(angle)
    local_x, local_y = c * (X - origin[0]) + s * (Y - origin[1]), -s * (X - origin[0]) + c * (Y - origin[1])
    values = np.asarray(g(local_x.ravel(), local_y.ravel()), dtype=float).reshape(X.shape)
    ax.contourf(X, Y, values, levels=[-np.inf, 0], colors=[color], alpha=0.12)


def _draw_forces(ax, pairs: dict, state, largest: float, color: str, to_doc: float, span: float) -> None:
    """Each touching pair's force on its site, an arrow ending at the contact point."""
    if largest <= 0:
        return
    for j, pair_state in enumerate(state.pair_states):
        if pair_state == "open":
            continue
        point = pairs["point"][:, j] * to_doc
        force = pairs["force"][:, j] / largest
        ax.annotate(
            "",
            xy=point,
            xytext=point - ARROW_SPAN * force * span,
            arrowprops=dict(arrowstyle="->", color=color, linewidth=1.2),
        )


def plot_states(mech, problem, states, labels, path: str | Path) -> Path:
    path = check_plot_path(path)
    return save_figure(states_figure(mech, problem, states, labels), path)


def path_figure(curves: list[tuple[str, np.ndarray, np.ndarray]], x_label: str, y_label: str, title: str) -> Figure:
    """y against x, one curve per (label, x, y)."""
    fig = new_figure(7.0, 4.5)
    ax = fig.add_subplot()
    for label, x, y in curves:
        ax.plot(x, y, marker=".", markersize=3, linewidth=1.2, label=label)
    set_labels(ax, x_label, y_label, title, legend=len(curves) > 1)
    return fig


def plot_path(curves, x_label: str, y_label: str, title: str, path: str | Path) -> Path:
    path = check_plot_path(path)
    return save_figure(path_figure(curves, x_label, y_label, title), path)
