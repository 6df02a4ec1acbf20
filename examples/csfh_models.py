"""Seed 004's four models on its three scenarios, with figures like the paper's Figs. 6, 8,
10, 11 and 12: x, y, theta, F_N and F_T of body 1 against time, and the path of G1 inside
the clearance circle, the four models overlaid.

  LNA K spheres    Lankarani-Nikravesh, Eq. 14 stiffness (Table 2: 47.353e9 N/m^1.5, with
                   E = 210 GPa and the external-contact radius R1 R2 / (R1 + R2)), Ambrosio
  LNA K cylinders  Lankarani-Nikravesh, Eq. 16 stiffness (Table 2: 2.2656e9, E = 210 GPa,
                   L = b = 25 mm), Ambrosio
  LNA-ESDU         Eq. 24 with the ESDU law (Eq. 18) solved exactly, Table 1's E = 100 GPa,
                   L = 25 mm, Ambrosio
  Moreau           Moreau-Jean, h = 1e-5 s, e_N = 0.9, f_a = 0.11, f_d = 0.055

    python3 examples/csfh_models.py [OUT_DIR] [--until 1.0]
"""

from __future__ import annotations

import argparse
import copy
import json
from pathlib import Path

from flexmech.models.documents.document import MechanismDocument
from flexmech.models.documents.simulation_spec import SimulateSpec
from flexmech.service.impacts.figures import plot_impacts
from flexmech.service.impacts.run import run_impacts

HERE = Path(__file__).resolve().parent
SCENARIOS = {"6.1": "csfh_central_impact.json", "6.2": "csfh_asymmetric_impact.json", "6.3": "csfh.json"}
AMBROSIO = {"law": "ambrosio", "sliding": 0.055, "adherence": 0.11, "v0": 1e-4, "v1": 1e-2}
MODELS = {
    "LNA K spheres": (
        {
            "law": "lankarani_nikravesh",
            "restitution": 0.9,
            "exponent": 1.5,
            "stiffness": {"contact": "spheres", "radius": "external", "materials": ["table2", "table2"]},
        },
        AMBROSIO,
        {},
    ),
    "LNA K cylinders": (
        {
            "law": "lankarani_nikravesh",
            "restitution": 0.9,
            "exponent": 1.5,
            "stiffness": {"contact": "cylinders", "length": 0.025, "materials": ["table2", "table2"]},
        },
        AMBROSIO,
        {},
    ),
    "LNA-ESDU": (
        {
            "law": "lna_esdu",
            "restitution": 0.9,
            "exponent": 1.5,
            "length": 0.025,
            "materials": ["body", "body"],
            "stiffness": {"contact": "cylinders", "length": 0.025, "materials": ["body", "body"]},
        },
        AMBROSIO,
        {},
    ),
    "Moreau": (
        {"law": "restitution", "restitution": 0.9},
        {"law": "coulomb", "adherence": 0.11, "sliding": 0.055},
        {"scheme": "moreau", "step": 1e-5},
    ),
}


def model_document(scenario: str, model: str, until: float) -> dict:
    doc = json.loads((HERE / SCENARIOS[scenario]).read_text())
    normal, friction, simulate = MODELS[model]
    pair = doc["contacts"]["pairs"]["conjugate"]
    pair["normal"], pair["friction"] = copy.deepcopy(normal), copy.deepcopy(friction)
    doc["simulate"].update(until=until, **simulate)
    return doc


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", nargs="?", default="csfh_figures")
    parser.add_argument("--until", type=float, default=1.0)
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for scenario in SCENARIOS:
        reports = []
        for model in MODELS:
            doc = model_document(scenario, model, args.until)
            _, report = run_impacts(MechanismDocument.model_validate(doc), SimulateSpec.model_validate(doc["simulate"]))
            reports.append(report)
            first = report["impacts"][0] if report["impacts"] else None
            peak = max(report["contacts"]["conjugate"]["normal_force"])
            print(
                f"{scenario} {model:16s} {report['status']}: {report['steps']} steps in {report['seconds']:.3f} s; "
                + (f"first impact {first['time']:.6f} s at {first['impact_speed']:.6f} m/s; " if first else "")
                + f"peak F_N {peak:.4g} N; balance error {report['energy_balance_error']:.1e}"
            )
        figure = out / f"csfh_{scenario}.png"
        plot_impacts(reports, figure, labels=list(MODELS))
        print(f"wrote {figure}")


if __name__ == "__main__":
    main()
