"""Documents of seed 004's conjugate-surface flexure hinge for the impact tests, built from
the shipped examples with changes."""

from __future__ import annotations

import copy
import json
from pathlib import Path

from models.document import MechanismDocument
from models.simulation_spec import SimulateSpec

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def csfh(scenario: str = "6.3", **simulate) -> dict:
    name = {"6.1": "csfh_central_impact.json", "6.2": "csfh_asymmetric_impact.json", "6.3": "csfh.json"}[scenario]
    doc = json.loads((EXAMPLES / name).read_text())
    doc["simulate"].update(simulate)
    return doc


def with_pair(doc: dict, **changes) -> dict:
    doc = copy.deepcopy(doc)
    pair = doc["impacts"]["pairs"]["conjugate"]
    for key, value in changes.items():
        if key in ("law", "restitution", "stiffness", "exponent"):
            pair["normal"][key] = value
        else:
            pair["friction"] = value
    return doc


def parsed(doc: dict) -> tuple[MechanismDocument, SimulateSpec]:
    document = MechanismDocument.model_validate(doc)
    return document, SimulateSpec.model_validate(doc["simulate"])
