"""The gripper of Cammarata et al. 2022 in three curved-beam models, silicon and nylon: closing forces, one figure.

The models are linear, partial non-linear and the exact elastica of the arc. The figure has
a row per material: the end-effector trajectory, and the actuation force against the
end-effector x, over the opening-closing movement (F from -60 uN to closing; nylon from
-60 uN scaled by E_nylon / E_silicon). Nylon's loads are silicon's scaled with E, so both
materials follow the same trajectory, with forces in the ratio of their E: each has its own
panels, so that neither hides the other.

    python3 examples/compare_gripper_models.py [--out gripper_models.png] [--steps 100]
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexmech.models import COMPARED_MODELS, compile_mechanism, load_document
from flexmech.service import solve_for_target, sweep

HERE = Path(__file__).resolve().parent
ACTUATION = "/loads/actuation/force/1"
MATERIALS = {"silicon": HERE / "gripper.json", "nylon": HERE / "gripper_nylon.json"}
STYLES = {"linear": ("C0", "-"), "partial_nonlinear": ("C1", "--"), "exact": ("C2", ":")}


@dataclass
class Curve:
    """One material and model over the opening-closing movement, document units."""

    material: str
    model: str
    closing_force: float
    x: np.ndarray  # end-effector x
    y: np.ndarray  # end-effector y
    force: np.ndarray  # actuation force
    length_unit: str
    force_unit: str


def material_curves(material: str, path: Path, steps: int, opening: float) -> list[Curve]:
    """Each model's closing force and movement from `opening` (document force unit) to
    closing, in steps; prints the closing forces and how far each is from the exact one."""
    curves = []
    for model in COMPARED_MODELS:
        mech = compile_mechanism(load_document(path), model=model)
        target = solve_for_target(mech, ACTUATION, "end_effector.x", 0.0)
        if target.status != "converged":
            print(f"{material:8s} {model:18s} closing not reached: {target.status}")
            continue
        result = sweep(mech, ACTUATION, np.linspace(opening, target.value, steps + 1))
        unit = mech.doc_unit("force")
        curves.append(
            Curve(
                material,
                model,
                target.value,
                result.outputs["end_effector.x"],
                result.outputs["end_effector.y"],
                result.values,
                mech.doc_unit("length"),
                unit,
            )
        )
        print(f"{material:8s} {model:18s} {target.value:11.4f} {unit}  {target.equilibrium.iterations:10d}")
    exact = [c.closing_force for c in curves if c.model == "exact"]
    for curve in curves if exact else []:
        if curve.model != "exact":
            print(
                f"{'':8s} {curve.model:18s} differs from exact by {100 * (curve.closing_force / exact[0] - 1):+.2f} %"
            )
    return curves


def models_figure(curves: dict[str, list[Curve]]):
    """A row per material: its end-effector trajectories, and its actuation force against the
    end-effector x, a line per model. Returns the matplotlib Figure."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 4.2 * len(curves)), layout="constrained")
    FigureCanvasAgg(fig)
    rows = fig.subplots(len(curves), 2, squeeze=False)
    for (material, lines), (trajectory, force) in zip(curves.items(), rows):
        for c in lines:
            color, style = STYLES.get(c.model, ("C3", "-"))
            trajectory.plot(c.x, c.y, style, color=color, label=c.model)
            force.plot(
                c.x, c.force, style, color=color, label=f"{c.model}: closes at {c.closing_force:.4g} {c.force_unit}"
            )
        unit, force_unit = (lines[0].length_unit, lines[0].force_unit) if lines else ("", "")
        for ax, title, ylabel in (
            (trajectory, f"{material}: end-effector trajectory", f"end_effector.y [{unit}]"),
            (force, f"{material}: actuation force against end-effector x", f"actuation force [{force_unit}]"),
        ):
            ax.set_title(title, fontsize=10)
            ax.set(xlabel=f"end_effector.x [{unit}]", ylabel=ylabel)
            ax.grid(True, linewidth=0.4, alpha=0.5)
            ax.legend(fontsize=8)
    fig.suptitle("Gripper of Cammarata et al. 2022: linear, partial non-linear and exact curved beams", fontsize=11)
    return fig


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="gripper_models.png")
    parser.add_argument("--steps", type=int, default=100)
    args = parser.parse_args()

    print(f"{'material':8s} {'model':18s} {'closing force':>14s}  {'iterations':>10s}")
    silicon_E = compile_mechanism(load_document(MATERIALS["silicon"])).value("/materials/silicon/E")
    curves = {}
    for material, path in MATERIALS.items():
        ratio = compile_mechanism(load_document(path)).value(f"/materials/{material}/E") / silicon_E
        curves[material] = material_curves(material, path, args.steps, -60.0 * ratio)  # the paper's opening force
    models_figure(curves).savefig(args.out, dpi=130)
    print(f"figure: {args.out}")


if __name__ == "__main__":
    main()
