"""Figures of an impact simulation, like seed 004's: x, y, theta, F_N and F_T of each moving
body and pair against time (Figs. 6, 8, 11), and the path of each mass centre inside the
clearance circle (Figs. 10, 12). Several reports overlay (the four models)."""

from __future__ import annotations

import numpy as np


def plot_impacts(reports: dict | list[dict], path, labels: list[str] | None = None) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    reports = [reports] if isinstance(reports, dict) else reports
    labels = labels or [r["scheme"]["name"] for r in reports]
    first = reports[0]
    coordinates = list(first["coordinates"])
    pair = next(iter(first["contacts"]))
    rows = coordinates + [f"{pair}: F_N", f"{pair}: F_T"]
    fig = plt.figure(figsize=(12, 2.0 * len(rows)))
    grid = fig.add_gridspec(len(rows), 2, width_ratios=(2.2, 1))
    units = first["units"]
    for k, name in enumerate(rows):
        ax = fig.add_subplot(grid[k, 0])
        for report, label in zip(reports, labels):
            t = np.asarray(report["times"])
            if name in report["coordinates"]:
                values = report["coordinates"][name]
                unit = units["angle"] if name.endswith(".theta") else units["length"]
            else:
                key = "normal_force" if name.endswith("F_N") else "friction_force"
                values, unit = report["contacts"][pair][key], units["force"]
            ax.plot(t, values, lw=0.8, label=label)
        if name not in first["coordinates"] and len(reports) > 1:  # impulses / h dwarf the regularized forces
            ax.set_yscale("symlog", linthresh=10.0)
        ax.set_ylabel(f"{name} ({unit})", fontsize=8)
        ax.grid(alpha=0.3)
        if k == 0 and len(reports) > 1:
            ax.legend(fontsize=7, ncol=len(reports))
    ax.set_xlabel("t (s)")
    path_ax = fig.add_subplot(grid[:, 1])
    body = coordinates[0].rsplit(".", 1)[0]
    for report, label in zip(reports, labels):
        path_ax.plot(report["coordinates"][f"{body}.x"], report["coordinates"][f"{body}.y"], lw=0.6, label=label)
    clearance = first.get("clearance")
    if clearance:
        angle = np.linspace(0, 2 * np.pi, 361)
        path_ax.plot(clearance * np.cos(angle), clearance * np.sin(angle), "k--", lw=0.8, label="clearance")
    path_ax.set_aspect("equal")
    path_ax.set_xlabel(f"{body}.x ({units['length']})")
    path_ax.set_ylabel(f"{body}.y ({units['length']})")
    path_ax.set_title("path of the mass centre", fontsize=9)
    path_ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
