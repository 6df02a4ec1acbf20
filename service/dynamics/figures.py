"""Figures of a simulation: outputs and energies against time, snapshots of the deformed
links, and an animation of them (GIF through Pillow, MP4 through ffmpeg when installed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from flexmech.models import Mechanism
from flexmech.service.display import on_axis
from flexmech.service.dynamics.integrate import History
from flexmech.service.dynamics.state_map import state_map


def plot_history(report: dict, outputs: list[str], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.array(report["times"])
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    for name in outputs:
        top.plot(t, report["outputs"][name], label=name)
    top.set_ylabel("outputs (document units)")
    top.legend(fontsize=8)
    energies = report["energies"]
    keys = [k for k in ENERGY_CURVES if np.any(np.array(energies.get(k, [0])) != 0)]
    unit, shown = on_axis(report["units"]["energy"], [energies[k] for k in keys], "energy")  # in J
    for key, values in zip(keys, shown):
        bottom.plot(t, values, label=ENERGY_CURVES[key])
    bottom.set_xlabel("t (s)")
    bottom.set_ylabel(f"energy ({unit})")
    bottom.legend(fontsize=8)
    error = report["energy_balance_error"]
    balance = "-" if error is None else f"{100 * error:.3g} % of the largest energy (relative)"
    top.set_title(f"{report['name']}\n{report['status']}, energy balance error {balance}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


ENERGY_CURVES = {
    "kinetic": "kinetic T",
    "potential": "strain and gravity V",
    "input_work": "work of inputs",
    "damping_work": "work of damping",
    "friction_work": "work of friction",
    "contact_damping_work": "work of contact damping",
    "balance": "balance",
}


def _centre_lines(mech: Mechanism, history: History, chosen) -> list[np.ndarray]:
    form = state_map(mech.structure)
    scale = mech.scales.length / mech.doc_factor("length")
    return [
        np.asarray(mech.graphs.shapes(form.to_state(history.x[k], history.lam[k]), history.p[k])[0]) * scale
        for k in chosen
    ]


def draw_snapshots(mech: Mechanism, history: History, path: Path, count: int = 6) -> None:
    """The links at `count` kept states spread over the run, overlaid, lighter when earlier."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    chosen = np.unique(np.linspace(0, len(history.times) - 1, min(count, len(history.times))).astype(int))
    fig, ax = plt.subplots(figsize=(6, 6))
    for shade, (k, line) in enumerate(zip(chosen, _centre_lines(mech, history, chosen))):
        colour = plt.cm.viridis(shade / max(len(chosen) - 1, 1))
        for index, (_, first, columns, _, _) in enumerate(mech.graphs.shape_segments):
            ax.plot(
                line[0, first : first + columns],
                line[1, first : first + columns],
                color=colour,
                lw=2,
                label=f"t = {history.times[k]:.3f} s" if index == 0 else None,
            )
    ax.set_aspect("equal")
    ax.set_xlabel(f"x ({mech.doc_unit('length')})")
    ax.set_ylabel(f"y ({mech.doc_unit('length')})")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def animate(mech: Mechanism, history: History, path: Path, frames: int = 100) -> None:
    """The deformed links at up to `frames` kept states, 25 frames per second."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation

    chosen = np.unique(np.linspace(0, len(history.times) - 1, min(frames, len(history.times))).astype(int))
    shapes = _centre_lines(mech, history, chosen)
    every = np.hstack(shapes)
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.set_aspect("equal")
    margin = 0.05 * max(np.ptp(every[0]), np.ptp(every[1]), 1e-12)
    ax.set_xlim(every[0].min() - margin, every[0].max() + margin)
    ax.set_ylim(every[1].min() - margin, every[1].max() + margin)
    ax.set_xlabel(f"x ({mech.doc_unit('length')})")
    ax.set_ylabel(f"y ({mech.doc_unit('length')})")
    lines = [ax.plot([], [], lw=2)[0] for _ in mech.graphs.shape_segments]
    label = ax.set_title("")

    def draw(i):
        for line, (_, first, count, _, _) in zip(lines, mech.graphs.shape_segments):
            line.set_data(shapes[i][0, first : first + count], shapes[i][1, first : first + count])
        label.set_text(f"t = {history.times[chosen[i]]:.3f} s")
        return [*lines, label]

    movie = animation.FuncAnimation(fig, draw, frames=len(shapes), blit=False)
    writer = animation.PillowWriter(fps=25) if path.suffix.lower() == ".gif" else animation.FFMpegWriter(fps=25)
    movie.save(str(path), writer=writer)
    plt.close(fig)
