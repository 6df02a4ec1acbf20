"""The `impacts` section of a mechanism document: surfaces carried by bodies, and the pairs
of them that may touch, each with its normal law and friction.

    "impacts": {
      "surfaces": {"pin":  {"type": "circle", "body": "hinge", "centre": [0, 0], "radius": 0.18},
                   "hole": {"type": "hole", "body": "frame", "centre": [0, 0], "radius": 0.20}},
      "pairs": {"conjugate": {"surfaces": ["pin", "hole"],
                              "normal": {"law": "lankarani_nikravesh", "restitution": 0.9,
                                         "stiffness": {"contact": "cylinders", "length": 0.025,
                                                       "materials": ["steel", "steel"]}},
                              "friction": {"law": "ambrosio", "sliding": 0.055, "adherence": 0.11}}}
    }

The first surface of a pair is always a circle (the pin, a roller, a ball); the second is a
hole it sits in (conformal contact), a circle it meets from outside, or a line (the solid
half-plane behind it). Centres and points are in the carrying body's axes, from its
reference point. Stiffness and damping follow the paper's Eqs. 13-25; stiffness is in the
document's force / length^exponent unless computed from the materials.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from models.fields import Number, StrictModel, Vec2

NORMAL_LAWS = ("hertz", "hunt_crossley", "lankarani_nikravesh", "flores", "lna_esdu")


class CircleSurface(StrictModel):
    type: Literal["circle"]
    body: str
    centre: Vec2 = (0.0, 0.0)
    radius: Number


class HoleSurface(StrictModel):
    """A circular hole: the solid is outside the circle."""

    type: Literal["hole"]
    body: str
    centre: Vec2 = (0.0, 0.0)
    radius: Number


class LineSurface(StrictModel):
    """The solid half-plane behind the line through `point`; `normal` points out of it."""

    type: Literal["line"]
    body: str
    point: Vec2
    normal: Vec2


Surface = Annotated[CircleSurface | HoleSurface | LineSurface, Field(discriminator="type")]


class ComputedStiffness(StrictModel):
    """Hertz's generalized stiffness from geometry and materials: two spheres (Eq. 14, with
    the radius of external contact R1 R2 / (R1 + R2) or of a pin in a hole R1 R2 / (R2 - R1))
    or two cylinders of contact length L (Eq. 16, pi E* L / 4)."""

    contact: Literal["spheres", "cylinders"]
    materials: tuple[str, str] = Field(description="the two bodies' materials (E and nu)")
    radius: Literal["external", "conformal"] = Field(
        default="conformal", description="spheres: which effective radius (Table 2 of seed 004 uses external)")
    length: Number | None = Field(default=None, description="cylinders: the contact length")


class NormalLaw(StrictModel):
    law: Literal["hertz", "hunt_crossley", "lankarani_nikravesh", "flores", "lna_esdu"] = "lankarani_nikravesh"
    stiffness: Number | ComputedStiffness = Field(description="K (document force / length^exponent), or computed")
    exponent: float = Field(default=1.5, gt=0, le=3, description="n of F = K q^n")
    restitution: float = Field(default=0.9, description="c_r in (0, 1]: the laws' damping; moreau's e_N")
    length: Number | None = Field(default=None, description="lna_esdu: the contact length L of Eq. 18")
    materials: tuple[str, str] | None = Field(default=None, description="lna_esdu: the two materials (Eq. 18)")


class Friction(StrictModel):
    """Ambrosio's regularized law (Eq. 26: none below v0, growing to f_d at v1) for the
    event-driven models; Coulomb's with adherence f_a and sliding f_d in moreau."""

    law: Literal["ambrosio", "coulomb", "none"] = "ambrosio"
    sliding: float = Field(default=0.0, description="f_d, the dynamic coefficient")
    adherence: float | None = Field(default=None, description="f_a, the static coefficient (moreau; default f_d)")
    v0: float = Field(default=1e-4, gt=0, description="ambrosio: no friction below this slip speed (m/s)")
    v1: float = Field(default=1e-2, gt=0, description="ambrosio: full friction from this slip speed (m/s)")


class ImpactPair(StrictModel):
    surfaces: tuple[str, str] = Field(description="a circle, and the hole, circle or line it touches")
    normal: NormalLaw
    friction: Friction = Friction(law="none")


class Impacts(StrictModel):
    surfaces: dict[str, Surface] = Field(default={}, max_length=64)
    pairs: dict[str, ImpactPair] = Field(default={}, max_length=64)
    flexure_stiffness: Literal["constant", "turning"] = Field(
        default="constant", description="curved beams in impact simulations: the closed-form stiffness of seed 000 "
        "constant in space (conservative, the default), or turning with the body (seed 004 Eq. 8, not conservative)")
