"""Contact laws by name, each registered once, each naming the analyses that take it. A new
law is a module defining it (a NormalLaw or FrictionLaw) and one registration line below."""

from flexmech.models.contact.laws.friction import Ambrosio, Coulomb, NoFriction
from flexmech.models.contact.laws.impulsive import Restitution, Unilateral
from flexmech.models.contact.laws.penalty import (
    Flores,
    Hertz,
    HuntCrossley,
    LankaraniNikravesh,
    LinearSpringDashpot,
    LnaEsdu,
)
from flexmech.models.contact.laws.registry import (
    ANALYSES,
    FRICTION_LAWS,
    NORMAL_LAWS,
    FrictionLaw,
    NormalLaw,
    check_law,
    friction_law,
    normal_law,
    register_friction_law,
    register_normal_law,
)

register_normal_law(Unilateral())
register_normal_law(Restitution())
register_normal_law(Hertz())
register_normal_law(HuntCrossley())
register_normal_law(LankaraniNikravesh())
register_normal_law(Flores())
register_normal_law(LnaEsdu())
register_normal_law(LinearSpringDashpot())
register_friction_law(NoFriction())
register_friction_law(Coulomb())
register_friction_law(Ambrosio())

__all__ = [
    "ANALYSES",
    "FRICTION_LAWS",
    "NORMAL_LAWS",
    "FrictionLaw",
    "NormalLaw",
    "check_law",
    "friction_law",
    "normal_law",
    "register_friction_law",
    "register_normal_law",
]
