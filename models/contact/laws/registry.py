"""The registries of contact laws. A normal law says how a pair pushes (the exact unilateral
contact of a quasi-static solve, a penalty force of the indentation, Newton's restitution
impulses); a friction law how it resists sliding. Each law names the analyses that take it
(`ANALYSES`), so a document asking one of another is refused with what to use instead."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, cast  # CasADi expressions are Any to mypy

from flexmech.models.errors import MechanismError

# the analyses that use contact laws, and how a message names them
ANALYSES = {
    "contact": "a quasi-static contact solve",
    "event_driven": "an event_driven simulation",
    "moreau": "a moreau simulation",
    "link_dynamics": "a newmark or generalized_alpha simulation (and the equilibrium solve)",
}


@dataclass(frozen=True)
class NormalLaw:
    """A normal law. `needs`: the fields of the pair's `normal` it reads (stiffness,
    restitution, damping, length, materials). A penalty law gives its force F_N >= 0 at an
    indentation q > 0 (force); the others are enforced by their analysis."""

    name: str
    analyses: frozenset[str]
    summary: str
    needs: tuple[str, ...] = ()

    def force(self, pair: Any, q: Any, rate: Any, impact_speed: Any) -> Any:
        """F_N (CasADi) at indentation q > 0, its rate (positive approaching) and the rate
        frozen at the contact's onset; `pair` holds the law's numbers as symbols (K,
        exponent, restitution, damping, esdu)."""
        # unreachable through the service: check_law lets only penalty laws into a run that asks this
        raise TypeError(f"the {self.name} law has no penalty force: it is enforced by its analysis")


@dataclass(frozen=True)
class FrictionLaw:
    """A friction law. `speed_events`: its force changes regime at slip speeds v0 and v1,
    which the event-driven integrator locates (Ambrosio's)."""

    name: str
    analyses: frozenset[str]
    summary: str
    speed_events: bool = False

    def force(self, pair: Any, slip_speed: Any, normal_force: Any, beyond_v0: Any, beyond_v1: Any) -> Any:
        """F_T along the tangent (CasADi), for an event-driven simulation."""
        # unreachable through the service: check_law lets only regularized laws into a run that asks this
        raise TypeError(f"the {self.name} friction law has no regularized force: it is enforced by its analysis")


NORMAL_LAWS: dict[str, NormalLaw] = {}
FRICTION_LAWS: dict[str, FrictionLaw] = {}


def register_normal_law(law: NormalLaw) -> NormalLaw:
    _check_analyses(law)
    NORMAL_LAWS[law.name] = law
    return law


def register_friction_law(law: FrictionLaw) -> FrictionLaw:
    _check_analyses(law)
    FRICTION_LAWS[law.name] = law
    return law


def _check_analyses(law: NormalLaw | FrictionLaw) -> None:
    unknown = set(law.analyses) - set(ANALYSES)
    if unknown:
        raise ValueError(f"law '{law.name}' names analyses that use no contact law: {', '.join(sorted(unknown))}")


def normal_law(name: str, pointer: str) -> NormalLaw:
    return cast(NormalLaw, _known(NORMAL_LAWS, "normal", name, pointer))


def friction_law(name: str, pointer: str) -> FrictionLaw:
    return cast(FrictionLaw, _known(FRICTION_LAWS, "friction", name, pointer))


def _known(
    registry: Mapping[str, NormalLaw | FrictionLaw], kind: str, name: str, pointer: str
) -> NormalLaw | FrictionLaw:
    if name not in registry:
        raise MechanismError(pointer, f"unknown {kind} law '{name}'; the {kind} laws are {', '.join(registry)}")
    return registry[name]


def check_law(
    registry: Mapping[str, NormalLaw | FrictionLaw], kind: str, name: str, analysis: str, pointer: str
) -> None:
    """Refuse a law the analysis does not take, naming the laws it does."""
    law = _known(registry, kind, name, pointer)
    if analysis in law.analyses:
        return
    takes = [other.name for other in registry.values() if analysis in other.analyses]
    where = ", ".join(ANALYSES[a] for a in ANALYSES if a in law.analyses) or "no analysis yet"
    raise MechanismError(
        pointer,
        f"{ANALYSES[analysis]} does not take the {kind} law '{name}' (it is for {where}); "
        f"it takes {' or '.join(takes)}",
    )
