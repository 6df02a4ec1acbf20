"""Documents of an older shape, converted to today's (`flexmech upgrade DOC`). The service
refuses the old shapes with a message that names this conversion; nothing converts silently.

The `impacts` section (surfaces and pairs of a simulation with impacts) became part of
`contacts`: a pair's first surface (always a circle on a body) is a circle site, its second a
circle, hole or half_plane object (a `line` was the half-plane behind it), carried by the
same body; the normal law and friction carry over with their numbers, and the defaults the
old section had are written out (Lankarani-Nikravesh, Ambrosio's friction). A document whose
`simulate` runs the moreau scheme gets the laws moreau takes: restitution impulses with the
same coefficient, and Coulomb's friction with the same coefficients (the old section read
them so). `flexure_stiffness` moved to `simulate`.
"""

from __future__ import annotations

import copy
from typing import Any

from flexmech.models.errors import MechanismError

OBJECT_TYPES = {"circle": "circle", "hole": "hole", "line": "half_plane"}
OLD_NORMAL_LAW = "lankarani_nikravesh"  # the old section's defaults, written out
OLD_FRICTION_LAW = "ambrosio"


def upgraded(document: dict[str, Any]) -> tuple[dict[str, Any], list[str]]:
    """(the document in today's shape, what changed, one line each). A document already in
    today's shape comes back equal, with no changes listed."""
    if not isinstance(document, dict):
        raise MechanismError("", "a mechanism document must be a JSON object")
    if document.get("impacts") is None:
        return copy.deepcopy(document), []
    impacts = copy.deepcopy(document["impacts"])
    if not isinstance(impacts, dict):
        raise MechanismError("/impacts", "the old `impacts` section must be an object of surfaces and pairs")
    # `contacts` where `impacts` was (or where it already is): the document reads as before
    doc = {
        ("contacts" if key == "impacts" else key): copy.deepcopy(value)
        for key, value in document.items()
        if not (key == "impacts" and "contacts" in document)
    }
    contacts = doc["contacts"] if "contacts" in document else {}
    doc["contacts"] = contacts = contacts if isinstance(contacts, dict) else {}
    for key in ("sites", "objects", "pairs"):
        contacts.setdefault(key, {})
    moreau = (doc.get("simulate") or {}).get("scheme") == "moreau"
    changes = []
    surfaces, pairs = impacts.get("surfaces", {}), impacts.get("pairs", {})
    names = _place_surfaces(contacts, surfaces, pairs, changes)
    for name, pair in pairs.items():
        new_name = _free(contacts["pairs"], name)
        first, second = (pair.get("surfaces") or [None, None])[:2]
        contacts["pairs"][new_name] = {
            "site": names["sites"].get(first, first),
            "object": names["objects"].get(second, second),
            "normal": _normal(pair.get("normal", {}), moreau),
            "friction": _friction(pair.get("friction"), moreau),
        }
        changes.append(f"/impacts/pairs/{name} -> /contacts/pairs/{new_name}")
    stiffness = impacts.get("flexure_stiffness")
    if stiffness is not None and stiffness != "constant":
        doc.setdefault("simulate", {})["flexure_stiffness"] = stiffness
        changes.append("/impacts/flexure_stiffness -> /simulate/flexure_stiffness")
    return doc, changes


def _place_surfaces(contacts: dict, surfaces: dict, pairs: dict, changes: list[str]) -> dict[str, dict[str, str]]:
    """Each surface as a site (a pair's first) and an object (a pair's second, or any surface
    no pair names, by its type); the new names, where a name was taken."""
    firsts = {(pair.get("surfaces") or [None])[0] for pair in pairs.values()}
    seconds = {(pair.get("surfaces") or [None, None])[1] for pair in pairs.values()}
    names: dict[str, dict[str, str]] = {"sites": {}, "objects": {}}
    for name, surface in surfaces.items():
        kind = surface.get("type")
        as_site = name in firsts or (name not in seconds and kind == "circle")
        as_object = name in seconds or (name not in firsts and kind != "circle")
        if as_site:
            if kind != "circle":
                raise MechanismError(
                    f"/impacts/surfaces/{name}/type",
                    f"surface '{name}' is the first of a pair, so a circle; it is a {kind}",
                )
            new = names["sites"][name] = _free(contacts["sites"], name)
            contacts["sites"][new] = {key: value for key, value in surface.items()}
            changes.append(f"/impacts/surfaces/{name} -> /contacts/sites/{new}")
        if as_object:
            if kind not in OBJECT_TYPES:
                raise MechanismError(
                    f"/impacts/surfaces/{name}/type", f"unknown surface type '{kind}' (circle, hole, line)"
                )
            new = names["objects"][name] = _free(contacts["objects"], name)
            placed = {**surface, "type": OBJECT_TYPES[kind]}
            if kind != "line":
                placed.setdefault("centre", [0.0, 0.0])  # an object's centre has no default
            contacts["objects"][new] = placed
            changes.append(f"/impacts/surfaces/{name} -> /contacts/objects/{new}")
    return names


def _normal(normal: dict, moreau: bool) -> dict:
    if moreau:  # moreau read only the restitution of any law: Newton's impulses with it
        return {"law": "restitution", "restitution": normal.get("restitution", 0.9)}
    return {"law": OLD_NORMAL_LAW, **normal}


def _friction(friction: dict | None, moreau: bool) -> dict:
    if friction is None:
        return {"law": "none"}
    law = friction.get("law", OLD_FRICTION_LAW)
    if moreau and law != "none":  # moreau read Coulomb's coefficients of any law
        return {"law": "coulomb", **{key: friction[key] for key in ("sliding", "adherence") if key in friction}}
    return {**friction, "law": law}


def _free(taken: dict, name: str) -> str:
    """`name`, or the first of name_impact, name_impact2, ... that is not taken."""
    if name not in taken:
        return name
    candidate, k = f"{name}_impact", 2
    while candidate in taken:
        candidate, k = f"{name}_impact{k}", k + 1
    return candidate
