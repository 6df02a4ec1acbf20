"""Figures of vibration: mode shapes drawn over the mechanism at its state, a mode animated (GIF),
and Bode plots of a frequency response.

A mode is drawn from its report: the drawn centre lines at the state (`lines`) and the bodies
(`bodies`: each a skeleton from its reference point to the element ends it carries, the rigid
links between the elements) moved by a multiple of the mode's displacement of them
(`shape.lines`, `shape.bodies`), the multiple that moves the farthest-moving point by SHOWN of
the mechanism's size; the figure states that size of motion. Every mode of the report is drawn,
a panel each in a grid. Each figure is built by a *_figure function that returns the matplotlib
Figure (so that it can be inspected) and written by its plot_* counterpart."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from flexmech.models import MechanismError
from flexmech.service.drawings.figures import field_label, new_figure, save_figure, set_labels

if TYPE_CHECKING:
    from matplotlib.figure import Figure

SHOWN = 0.12  # the drawn amplitude, of the mechanism's size
FRAMES = 40
PANEL = 3.6  # inches: a mode's panel, while the grid is at most WIDEST wide
WIDEST = 20.0


class Drawn:
    """A mode's drawing: every element's centre line and every body's skeleton at `phase`
    (-1 to 1) of its drawn swing, each a 2 x points array (document length units)."""

    def __init__(self, report: dict, mode: dict):
        self.rest = {name: np.array(points, dtype=float).T for name, points in report["lines"].items()}
        shape = mode.get("shape") or {}
        self.moves = {name: np.array(points, dtype=float).T for name, points in shape.get("lines", {}).items()}
        self.bodies = report.get("bodies") or {}
        self.body_moves = {name: np.array(v[:2], dtype=float) for name, v in (shape.get("bodies") or {}).items()}
        references = [np.array(body["reference"], dtype=float)[:, None] for body in self.bodies.values()]
        every = np.hstack(list(self.rest.values()) + references)
        self.size = float(max(np.ptp(every[0]), np.ptp(every[1]), 1e-300))
        most = max((np.hypot(*d).max(initial=0.0) for d in self.moves.values()), default=0.0)
        most = max([most, *(float(np.hypot(*d)) for d in self.body_moves.values())])
        self.scale = SHOWN * self.size / most if most > 0 else 0.0

    def lines(self, phase: float) -> dict[str, np.ndarray]:
        return {name: line + phase * self.scale * self.moves.get(name, 0 * line) for name, line in self.rest.items()}

    def reference(self, body: str, phase: float) -> np.ndarray:
        point = np.array(self.bodies[body]["reference"], dtype=float)
        return point + phase * self.scale * self.body_moves.get(body, np.zeros(2))

    def skeletons(self, phase: float) -> dict[str, list[np.ndarray]]:
        """Per body, a 2 x 2 line from its reference point to each element end it carries."""
        lines = self.lines(phase)
        out: dict[str, list[np.ndarray]] = {}
        for body, drawn in self.bodies.items():
            reference = self.reference(body, phase)
            out[body] = [
                np.column_stack([reference, lines[element][:, 0 if end == "start" else -1]])
                for element, end in drawn["ends"]
                if element in lines
            ]
        return out


def _checked(report: dict) -> None:
    if not report.get("lines"):
        raise MechanismError("/shapes", "the figures draw the modes' shapes: leave `shapes` on")


def _grid(count: int) -> tuple[int, int, float]:
    """(rows, columns, panel width in inches) of a grid of `count` panels."""
    columns = min(count, max(3, math.ceil(math.sqrt(count))))
    return math.ceil(count / columns), columns, min(PANEL, WIDEST / columns)


def _draw_mode(ax, drawn: Drawn, colour: str, phase: float, width: float) -> None:
    for line in drawn.lines(phase).values():
        ax.plot(line[0], line[1], color=colour, lw=width)
    for body, skeleton in drawn.skeletons(phase).items():
        fixed = drawn.bodies[body]["fixed"]
        for link in skeleton:
            ax.plot(link[0], link[1], color=colour, lw=0.8 * width, ls="-" if not fixed else ":")
        if skeleton or fixed:
            reference = drawn.reference(body, phase)
            ax.plot(*reference, marker="s" if fixed else "o", color=colour, markersize=3 * width, ls="none")


def modes_figure(report: dict, length_unit: str) -> Figure:
    """Every reported mode over the mechanism at its state (grey), a panel each in a grid: the
    elements' centre lines and the bodies (reference points, squares if fixed, and the rigid
    links to the element ends they carry), each mode scaled so that its farthest-moving point
    moves SHOWN of the mechanism's size, which the figure states."""
    _checked(report)
    modes = report["modes"]
    rows, columns, panel = _grid(len(modes))
    fig = new_figure(panel * columns, 0.95 * panel * rows + 0.6)
    small = panel < PANEL
    size = None
    for k, mode in enumerate(modes):
        ax = fig.add_subplot(rows, columns, k + 1)
        drawn = Drawn(report, mode)
        size = drawn.size
        _draw_mode(ax, drawn, "0.7", 0.0, 1.5)
        _draw_mode(ax, drawn, "C0", 1.0, 2.0)
        frequency = f"{mode['frequency']:.5g} Hz" if mode["frequency"] is not None else mode["kind"]
        ax.set_aspect("equal")
        last_row, first_column = k >= len(modes) - columns, k % columns == 0
        set_labels(
            ax,
            f"x ({length_unit})" if last_row or not small else "",
            f"y ({length_unit})" if first_column or not small else "",
            f"mode {mode['mode']}: {frequency}",
            legend=False,
        )
        if small:
            ax.tick_params(labelsize=7)
    fig.suptitle(
        f"{report['name']} ({report['at']}): {len(modes)} modes\n"
        f"each shape scaled so that its largest motion is {SHOWN:.0%} of the mechanism's size "
        f"({SHOWN * (size or 0.0):.3g} {length_unit}); grey: the state",
        fontsize=10,
    )
    return fig


def plot_modes(report: dict, path: Path, length_unit: str) -> Path:
    """modes_figure saved to `path` (.png or .svg)."""
    return save_figure(modes_figure(report, length_unit), path)


def animate_mode(report: dict, mode: int, path: Path, length_unit: str) -> Path:
    """Mode `mode` (1-based) swinging through one period over FRAMES frames (GIF): its elements
    and bodies, scaled as modes_figure scales them."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation

    _checked(report)
    shown = report["modes"][mode - 1]
    drawn = Drawn(report, shown)
    phases = [math.sin(2 * math.pi * i / FRAMES) for i in range(FRAMES)]
    frames = [_frame(drawn, phase) for phase in phases]
    every = np.hstack([line for frame in frames for line in frame])
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.set_aspect("equal")
    margin = 0.05 * max(np.ptp(every[0]), np.ptp(every[1]), 1e-12)
    ax.set_xlim(every[0].min() - margin, every[0].max() + margin)
    ax.set_ylim(every[1].min() - margin, every[1].max() + margin)
    ax.set_xlabel(f"x ({length_unit})")
    ax.set_ylabel(f"y ({length_unit})")
    _draw_mode(ax, drawn, "0.75", 0.0, 1.5)
    elements = len(drawn.rest)
    drawn_lines = [ax.plot([], [], lw=2 if k < elements else 1.6, color="C0")[0] for k in range(len(frames[0]))]
    frequency = f"{shown['frequency']:.5g} Hz" if shown["frequency"] is not None else shown["kind"]
    ax.set_title(f"mode {mode}: {frequency} (largest motion drawn {SHOWN * drawn.size:.3g} {length_unit})")

    def draw(i: int):
        for line, points in zip(drawn_lines, frames[i]):
            line.set_data(points[0], points[1])
        return drawn_lines

    movie = animation.FuncAnimation(fig, draw, frames=FRAMES, blit=False)
    movie.save(str(path), writer=animation.PillowWriter(fps=20))
    plt.close(fig)
    return path


def _frame(drawn: Drawn, phase: float) -> list[np.ndarray]:
    """The elements' lines, then the bodies' links, at `phase`."""
    return list(drawn.lines(phase).values()) + [link for links in drawn.skeletons(phase).values() for link in links]


def plot_bode(report: dict, path: Path) -> Path:
    """Amplitude (log-log) and phase of every output against frequency, the resonances marked."""
    fig = new_figure(7.5, 6.0)
    amplitude, phase = fig.add_subplot(2, 1, 1), fig.add_subplot(2, 1, 2, sharex=None)
    f = np.array(report["frequencies"])
    for name, response in report["responses"].items():
        values = np.array([np.nan if a is None else a for a in response["amplitude"]], dtype=float)
        amplitude.loglog(f, values, label=f"{name} ({response['unit']})")
        phase.semilogx(f, np.array([np.nan if a is None else a for a in response["phase"]], dtype=float), label=name)
    for peak in report["resonances"]:
        amplitude.plot(peak["frequency"], peak["amplitude"], "k.", markersize=5)
    set_labels(amplitude, "", "|H| (output per unit load)", f"response to {field_label(report['input'])}")
    fig.suptitle(report["name"], fontsize=10)
    amplitude.legend(fontsize=8)
    set_labels(phase, "frequency (Hz)", "phase (deg)", "")
    return save_figure(fig, path)
