"""Figures of vibration: mode shapes drawn over the mechanism at its state, a mode animated (GIF),
and Bode plots of a frequency response.

A mode is drawn as the mechanism's centre lines at z + s v, v the mode over the residual form's
unknowns (service.vibration.sensitivity.state_mode) and s the amplitude that moves its largest
point by SHOWN of the mechanism's size: the elements' own unknowns follow, so links bend as the
mode bends them."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from models import Mechanism
from service.drawings.figures import field_label, new_figure, save_figure, set_labels
from service.vibration.sensitivity import state_mode

SHOWN = 0.12  # the drawn amplitude, of the mechanism's size
FRAMES = 40


def _centre_lines(mech: Mechanism, z: np.ndarray) -> np.ndarray:
    scale = mech.scales.length / mech.doc_factor("length")
    return np.asarray(mech.graphs.shapes(z, mech.p())[0], dtype=float) * scale


def _amplitude(mech: Mechanism, z: np.ndarray, v: np.ndarray) -> float:
    """s such that z + s v moves the drawing's farthest-moving point by SHOWN of its size."""
    rest = _centre_lines(mech, z)
    size = max(np.ptp(rest[0]), np.ptp(rest[1]), 1e-300)
    probe = 1e-6 / max(np.abs(v).max(), 1e-300)
    moved = np.abs(_centre_lines(mech, z + probe * v) - rest).max() / probe
    return SHOWN * size / max(moved, 1e-300)


def _draw(ax, mech: Mechanism, lines: np.ndarray, **style) -> None:
    for _, first, columns, _, _ in mech.graphs.shape_segments:
        ax.plot(lines[0, first : first + columns], lines[1, first : first + columns], **style)


def plot_modes(mech: Mechanism, z: np.ndarray, report: dict, path: Path) -> Path:
    """Each reported mode (up to six) over the mechanism at rest, grey."""
    modes = [m for m in report["modes"]][:6]
    columns = min(3, len(modes))
    rows = math.ceil(len(modes) / columns)
    fig = new_figure(4.0 * columns, 3.6 * rows)
    rest = _centre_lines(mech, z)
    for k, mode in enumerate(modes):
        ax = fig.add_subplot(rows, columns, k + 1)
        v, _ = state_mode(mech, z, mech.p(), mode["mode"] - 1)
        _draw(ax, mech, rest, color="0.7", lw=1.5)
        _draw(ax, mech, _centre_lines(mech, z + _amplitude(mech, z, v) * v), color="C0", lw=2)
        frequency = f"{mode['frequency']:.5g} Hz" if mode["frequency"] is not None else mode["kind"]
        ax.set_aspect("equal")
        set_labels(
            ax,
            f"x ({mech.doc_unit('length')})",
            f"y ({mech.doc_unit('length')})",
            f"mode {mode['mode']}: {frequency}",
            legend=False,
        )
    fig.suptitle(f"{report['name']} ({report['at']})", fontsize=11)
    return save_figure(fig, path)


def animate_mode(mech: Mechanism, z: np.ndarray, report: dict, mode: int, path: Path) -> Path:
    """Mode `mode` (1-based) swinging through one period over FRAMES frames (GIF)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation

    v, _ = state_mode(mech, z, mech.p(), mode - 1)
    s = _amplitude(mech, z, v)
    frames = [_centre_lines(mech, z + s * math.sin(2 * math.pi * i / FRAMES) * v) for i in range(FRAMES)]
    every = np.hstack(frames)
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.set_aspect("equal")
    margin = 0.05 * max(np.ptp(every[0]), np.ptp(every[1]), 1e-12)
    ax.set_xlim(every[0].min() - margin, every[0].max() + margin)
    ax.set_ylim(every[1].min() - margin, every[1].max() + margin)
    _draw(ax, mech, _centre_lines(mech, z), color="0.75", lw=1.5)
    lines = [ax.plot([], [], lw=2, color="C0")[0] for _ in mech.graphs.shape_segments]
    shown = report["modes"][mode - 1]
    frequency = f"{shown['frequency']:.5g} Hz" if shown["frequency"] is not None else shown["kind"]
    ax.set_title(f"mode {mode}: {frequency}")

    def draw(i: int):
        for line, (_, first, count, _, _) in zip(lines, mech.graphs.shape_segments):
            line.set_data(frames[i][0, first : first + count], frames[i][1, first : first + count])
        return lines

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
