"""Documents of seed 004's conjugate-surface flexure hinge for the impact tests, built from
the shipped examples with changes."""

from __future__ import annotations

import copy
import json
from pathlib import Path

from flexmech.models.documents.document import MechanismDocument
from flexmech.models.documents.simulation_spec import SimulateSpec

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def csfh(scenario: str = "6.3", **simulate) -> dict:
    """A scenario's example with `simulate` fields over it; for the moreau scheme with the
    laws moreau takes (as_moreau)."""
    name = {"6.1": "csfh_central_impact.json", "6.2": "csfh_asymmetric_impact.json", "6.3": "csfh.json"}[scenario]
    doc = json.loads((EXAMPLES / name).read_text())
    doc["simulate"].update(simulate)
    if doc["simulate"].get("scheme") == "moreau":
        as_moreau(doc["contacts"]["pairs"]["conjugate"])
    return doc


def as_moreau(pair: dict) -> dict:
    """The pair (in place) with the laws a moreau run takes: restitution impulses with its
    coefficient, and Coulomb's friction with its coefficients."""
    pair["normal"] = {"law": "restitution", "restitution": pair["normal"].get("restitution", 0.9)}
    friction = pair.get("friction")
    if isinstance(friction, dict) and friction.get("law") != "none":
        pair["friction"] = {
            "law": "coulomb",
            **{key: friction[key] for key in ("sliding", "adherence") if key in friction},
        }
    return pair


def with_pair(doc: dict, **changes) -> dict:
    doc = copy.deepcopy(doc)
    pair = doc["contacts"]["pairs"]["conjugate"]
    for key, value in changes.items():
        if key in ("law", "restitution", "stiffness", "exponent"):
            pair["normal"][key] = value
        else:
            pair["friction"] = value
    return doc


def parsed(doc: dict) -> tuple[MechanismDocument, SimulateSpec]:
    document = MechanismDocument.model_validate(doc)
    return document, SimulateSpec.model_validate(doc["simulate"])
