"""The seed-000 gripper designed nominally and robustly against its etch (examples/gripper_robust.json),
each design's yield checked by Monte Carlo:

    python -m flexmech.examples.robust_gripper [--samples 4000] [--seed 1]

The nominal design maximizes the flexures' width h with the end effector reaching x <= 0.005 mm
under 50 uN; the robust one asks the same of the end effector's mean + 3 sigma (first order over
the tolerances section: sigma 0.1 um on h). Both designs are then made 4000 times in the computer
(the tolerance analysis: each sample solved) and their shares meeting the spec printed."""

from __future__ import annotations

import argparse
import copy
import json
from pathlib import Path

DOCUMENT = Path(__file__).resolve().parent / "gripper_robust.json"


def designs() -> dict[str, dict[str, float]]:
    """The nominal and the robust optimum: {label: {field: value}}."""
    import flexmech
    from flexmech.service.design.optimize import optimize
    from flexmech.service.design.problem import design_problem

    robust = json.loads(DOCUMENT.read_text())
    nominal = copy.deepcopy(robust)
    for constraint in nominal["optimize"]["constraints"]:
        constraint.pop("sigmas", None)
    out = {}
    for label, document in (("nominal", nominal), ("robust", robust)):
        mech = flexmech.load(document)
        found = optimize(design_problem(mech, mech.document.optimize)).best
        if found is None or found.status != "optimal":
            raise SystemExit(f"the {label} design did not solve: {found.status if found else 'no start'}")
        out[label] = dict(found.design)
    return out


def yields(found: dict[str, dict[str, float]], samples: int, seed: int) -> dict[str, dict]:
    """Each design's tolerance report (the document's scatter and specs, `samples` samples)."""
    import flexmech
    from flexmech.service.analysis import run_analysis
    from flexmech.service.solvers.newton import NewtonOptions

    mech = flexmech.load(DOCUMENT)
    options = {"samples": samples, "seed": seed, "outputs": ["end_effector.x"]}
    return {
        label: run_analysis(mech.with_values(d), "tolerance", NewtonOptions(), options) for label, d in found.items()
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=4000)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    found = designs()
    for label, report in yields(found, args.samples, args.seed).items():
        tip, share = report["responses"]["end_effector.x"], report["yield"]
        widths = ", ".join(f"{path.rsplit('/', 1)[1]} = {1000 * value:.3f} um" for path, value in found[label].items())
        print(
            f"{label:8s} {widths}: end effector {tip['nominal']:.4f} mm, sigma {tip['first_order']['std']:.4f} mm; "
            f"yield {100 * share['monte_carlo']:.2f} % +- {100 * share['standard_error']:.2f} % of {share['samples']} "
            f"(first order {100 * tip['spec_share_first_order']:.2f} %)"
        )


if __name__ == "__main__":
    main()
