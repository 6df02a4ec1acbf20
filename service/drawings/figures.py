"""What every figure shares: the formats, labels of fields and outputs with their units, a
figure on the Agg canvas (never pyplot: nothing global is touched, nothing left open), and
saving by the file's suffix."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # matplotlib is imported when a figure is drawn, not with the package
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from flexmech.models import Mechanism

PLOT_SUFFIXES = (".png", ".svg")


def check_plot_path(path: str | Path) -> Path:
    """The path as a Path; ValueError unless its suffix is one of PLOT_SUFFIXES."""
    path = Path(path)
    if path.suffix.lower() not in PLOT_SUFFIXES:
        raise ValueError(
            f"cannot tell the figure format of '{path}': use a name ending in {' or '.join(PLOT_SUFFIXES)}"
        )
    return path


def field_label(pointer: str) -> str:
    """A short reading of a numeric field's JSON pointer for axis labels:
    /loads/actuation/force/1 -> "actuation force y", /sections/flexure/h -> "flexure h"."""
    parts = [p for p in pointer.split("/") if p]
    if (
        len(parts) >= 2
        and parts[-1] in ("0", "1")
        and parts[-2] in ("force", "position", "center", "centre", "at", "offset", "point")
    ):
        parts[-1] = "xy"[int(parts[-1])]
    if len(parts) >= 3:
        parts = parts[1:]  # drop the collection: the name already says what it is
    return " ".join(parts) if parts else pointer


def output_unit(mech: Mechanism, name: str) -> str:
    """Document unit of the output `name`; KeyError if the mechanism has no such output."""
    names = mech.graphs.output_names
    if name not in names:
        raise KeyError(name)
    return mech.doc_unit(mech.graphs.output_kinds[names.index(name)])


def new_figure(width: float, height: float) -> Figure:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig: Figure, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, format=path.suffix.lower().lstrip("."), dpi=150)
    return path


def set_labels(ax: Axes, xlabel: str, ylabel: str, title: str, legend: bool = True) -> None:
    ax.set(xlabel=xlabel, ylabel=ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, linewidth=0.4, alpha=0.5)
    if legend:
        ax.legend(fontsize=8)
