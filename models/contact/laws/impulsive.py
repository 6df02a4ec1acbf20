"""Normal laws that no force function describes: the exact unilateral contact of a
quasi-static solve (h >= 0, its multipliers the contact forces) and Newton's restitution
impulses of Moreau-Jean time stepping."""

from __future__ import annotations

from dataclasses import dataclass

from flexmech.models.contact.laws.registry import NormalLaw


@dataclass(frozen=True)
class Unilateral(NormalLaw):
    name: str = "unilateral"
    analyses: frozenset[str] = frozenset({"contact"})
    summary: str = "exact non-penetration; the forces are the multipliers of the equilibrium problem"


@dataclass(frozen=True)
class Restitution(NormalLaw):
    name: str = "restitution"
    analyses: frozenset[str] = frozenset({"moreau"})
    summary: str = "Newton's impact law: the normal exit speed is -e_N times the impact speed (Moreau-Jean)"
    needs: tuple[str, ...] = ("restitution",)
