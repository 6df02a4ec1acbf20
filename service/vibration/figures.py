"""Figures of vibration: mode shapes drawn over the mechanism at its state, a mode animated (GIF),
and Bode plots of a frequency response.

A mode is drawn from its report: the drawn centre lines at the state (`lines`) moved by a
multiple of the mode's displacement of them (`shape.lines`), the multiple that moves the
farthest-moving point by SHOWN of the mechanism's size."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from flexmech.models import MechanismError
from flexmech.service.drawings.figures import field_label, new_figure, save_figure, set_labels

SHOWN = 0.12  # the drawn amplitude, of the mechanism's size
FRAMES = 40


def _moved(report: dict, mode: dict, phase: float) -> dict[str, np.ndarray]:
    """Each element's centre line (2 x points) at `phase` (-1 to 1) of the mode's drawn swing."""
    rest = {name: np.array(points, dtype=float).T for name, points in report["lines"].items()}
    shape = {
        name: np.array(points, dtype=float).T for name, points in (mode.get("shape") or {}).get("lines", {}).items()
    }
    every = np.hstack(list(rest.values()))
    size = max(np.ptp(every[0]), np.ptp(every[1]), 1e-300)
    most = max((np.hypot(*d).max(initial=0.0) for d in shape.values()), default=0.0)
    scale = SHOWN * size / most if most > 0 else 0.0
    return {name: line + phase * scale * shape.get(name, 0 * line) for name, line in rest.items()}


def _checked(report: dict) -> None:
    if not report.get("lines"):
        raise MechanismError("/shapes", "the figures draw the modes' shapes: leave `shapes` on")


def plot_modes(report: dict, path: Path, length_unit: str) -> Path:
    """Each reported mode (up to six) over the mechanism at its state, grey."""
    _checked(report)
    modes = report["modes"][:6]
    columns = min(3, len(modes))
    rows = math.ceil(len(modes) / columns)
    fig = new_figure(4.0 * columns, 3.6 * rows)
    for k, mode in enumerate(modes):
        ax = fig.add_subplot(rows, columns, k + 1)
        for line in _moved(report, mode, 0.0).values():
            ax.plot(line[0], line[1], color="0.7", lw=1.5)
        for line in _moved(report, mode, 1.0).values():
            ax.plot(line[0], line[1], color="C0", lw=2)
        frequency = f"{mode['frequency']:.5g} Hz" if mode["frequency"] is not None else mode["kind"]
        ax.set_aspect("equal")
        set_labels(ax, f"x ({length_unit})", f"y ({length_unit})", f"mode {mode['mode']}: {frequency}", legend=False)
    fig.suptitle(f"{report['name']} ({report['at']})", fontsize=11)
    return save_figure(fig, path)


def animate_mode(report: dict, mode: int, path: Path, length_unit: str) -> Path:
    """Mode `mode` (1-based) swinging through one period over FRAMES frames (GIF)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation

    _checked(report)
    shown = report["modes"][mode - 1]
    frames = [_moved(report, shown, math.sin(2 * math.pi * i / FRAMES)) for i in range(FRAMES)]
    every = np.hstack([line for frame in frames for line in frame.values()])
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.set_aspect("equal")
    margin = 0.05 * max(np.ptp(every[0]), np.ptp(every[1]), 1e-12)
    ax.set_xlim(every[0].min() - margin, every[0].max() + margin)
    ax.set_ylim(every[1].min() - margin, every[1].max() + margin)
    ax.set_xlabel(f"x ({length_unit})")
    ax.set_ylabel(f"y ({length_unit})")
    for line in frames[0].values():
        ax.plot(line[0], line[1], color="0.75", lw=1.5)
    names = list(frames[0])
    drawn = [ax.plot([], [], lw=2, color="C0")[0] for _ in names]
    frequency = f"{shown['frequency']:.5g} Hz" if shown["frequency"] is not None else shown["kind"]
    ax.set_title(f"mode {mode}: {frequency}")

    def draw(i: int):
        for line, name in zip(drawn, names):
            line.set_data(frames[i][name][0], frames[i][name][1])
        return drawn

    movie = animation.FuncAnimation(fig, draw, frames=FRAMES, blit=False)
    movie.save(str(path), writer=animation.PillowWriter(fps=20))
    plt.close(fig)
    return path


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
