"""The gripper of seed 000 with its four curved beams in the three models (linear, partial
non-linear, exact elastica), silicon and nylon: the closing force of each, and one figure
with the end-effector trajectories and the actuation force against the end-effector x over
the opening-closing movement (F from -60 uN to closing; nylon from -60/26.04 uN).

    python3 examples/compare_gripper_models.py [--out gripper_models.png] [--steps 100]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from models import MODELS, compile_mechanism, load_document
from service import solve_for_target, sweep

HERE = Path(__file__).resolve().parent
ACTUATION = "/loads/actuation/force/1"
MATERIALS = {"silicon": HERE / "gripper.json", "nylon": HERE / "gripper_nylon.json"}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="gripper_models.png")
    parser.add_argument("--steps", type=int, default=100)
    args = parser.parse_args()

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(15, 4.8), layout="constrained")
    FigureCanvasAgg(fig)
    trajectory, *force_axes = fig.subplots(1, 3)
    print(f"{'material':8s} {'model':18s} {'closing force':>14s}  {'iterations':>10s}")
    silicon_E = compile_mechanism(load_document(MATERIALS["silicon"])).value("/materials/silicon/E")
    for (material, path), force_ax in zip(MATERIALS.items(), force_axes):
        closing_forces = {}
        stiffness_ratio = compile_mechanism(load_document(path)).value(f"/materials/{material}/E") / silicon_E
        for style, model in zip(("-", "--", ":"), MODELS):
            mech = compile_mechanism(load_document(path), model=model)
            target = solve_for_target(mech, ACTUATION, "end_effector.x", 0.0)
            if target.status != "converged":
                print(f"{material:8s} {model:18s} closing not reached: {target.status}")
                continue
            closing_forces[model] = target.value
            start = -60.0 * stiffness_ratio  # the paper's opening force, scaled with E for nylon
            result = sweep(mech, ACTUATION, np.linspace(start, target.value, args.steps + 1))
            x, y = result.outputs["end_effector.x"], result.outputs["end_effector.y"]
            label = f"{material}, {model}"
            trajectory.plot(x, y, style, label=label, color="C0" if material == "silicon" else "C3")
            force_ax.plot(x, result.values, style, label=model, color="C0" if material == "silicon" else "C3")
            unit = mech.doc_unit("force")
            print(f"{material:8s} {model:18s} {target.value:11.4f} {unit}  {target.equilibrium.iterations:10d}")
        force_ax.set_title(f"{material}: actuation force against end-effector x", fontsize=10)
        force_ax.set_xlabel("end_effector.x [mm]")
        force_ax.set_ylabel("actuation force [uN]")
        force_ax.grid(True, linewidth=0.4, alpha=0.5)
        force_ax.legend(fontsize=8)
        if "exact" in closing_forces:
            for model, value in closing_forces.items():
                if model != "exact":
                    print(f"{'':8s} {model:18s} differs from exact by {100 * (value / closing_forces['exact'] - 1):+.2f} %")
    trajectory.set_title("end-effector trajectories", fontsize=10)
    trajectory.set_xlabel("end_effector.x [mm]")
    trajectory.set_ylabel("end_effector.y [mm]")
    trajectory.grid(True, linewidth=0.4, alpha=0.5)
    trajectory.legend(fontsize=7)
    fig.suptitle("seed-000 gripper: linear, partial non-linear and exact curved beams", fontsize=11)
    fig.savefig(args.out, dpi=130)
    print(f"figure: {args.out}")


if __name__ == "__main__":
    main()
