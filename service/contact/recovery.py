"""The thesis' way to contact forces (Lan 2005, Eqs. 6.6-6.10), as a labelled comparison:
the frictionless shape, the force recovered from the clamp moment M (Eq. 6.6, M = P_C x F
about the clamp of the link carrying the site), along the object's normal n (Eq. 6.8), split
with a friction part mu |F_n| along the tangent t (Eqs. 6.9-6.10):

    F = F_n (n + mu sigma t),   F_n = M / ((P_C - O) x (n + mu sigma t)).

The friction force is not a load on that shape, so it is no equilibrium with friction; the
consistent analysis is service.contact.solve. sigma is the consistent state's direction."""

from __future__ import annotations

import numpy as np

from flexmech.models import Mechanism
from flexmech.models.elements import FAMILIES

METHOD = (
    "Lan 2005 Eqs. 6.6-6.10: the frictionless shape, the force recovered from the clamp moment and split "
    "with |F_t| = mu |F_n|; the friction force is not a load on that shape (no equilibrium with friction)"
)


def carrying_link(mech: Mechanism, site) -> str | None:
    """The link whose clamp the site's force runs to: its own link, or the link ending on its body."""
    if site.link is not None:
        return site.link
    ends = [
        t.name
        for t in mech.structure.elements
        if getattr(FAMILIES.of(t), "centre_line_sites", False) and t.end_body == site.body
    ]
    return ends[0] if len(ends) == 1 else None


def recovered_forces(mech: Mechanism, frictionless_report: dict, consistent_report: dict) -> dict:
    """Per pair (documents units), the thesis' recovery from the frictionless state."""
    contacts = mech.structure.contacts
    out = {}
    for pair in contacts.pairs:
        site = contacts.sites[pair.site]
        link = carrying_link(mech, site)
        before, after = frictionless_report["pairs"][pair.name], consistent_report["pairs"][pair.name]
        if link is None or before["normal"] is None:
            out[pair.name] = None
            continue
        outputs = frictionless_report["outputs"]
        moment = outputs[f"elements.{link}.M_start"]
        clamp = np.array([outputs[f"elements.{link}.x_start"], outputs[f"elements.{link}.y_start"]])
        n = np.array(before["normal"])
        t = np.array([-n[1], n[0]])
        mu = mech.value(pair.friction_pointer)
        sigma = np.sign(after["friction_force"]) if after["state"] == "slipping" else 0.0
        direction = n + mu * sigma * t
        arm = np.array(before["point"]) - clamp
        normal_force = moment / (arm[0] * direction[1] - arm[1] * direction[0])
        out[pair.name] = {
            "force": (normal_force * direction).tolist(),
            "normal_force": normal_force,
            "friction_force": mu * sigma * normal_force,
            "point": before["point"],
            "clamp_moment": moment,
            "link": link,
        }
    return {"method": METHOD, "pairs": out}
