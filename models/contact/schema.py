"""The `contacts` section of a mechanism document: rigid objects, contact sites, and pairs.

    "contacts": {
      "objects": {"fixture": {"type": "circle", "centre": [78, 10.5], "radius": 8.9}},
      "sites":   {"jaw": {"type": "jaw", "body": "tip", "vertices": [[0, 0], [19, 1.6], [0, 10.46]]}},
      "pairs":   {"grip": {"site": "jaw", "object": "fixture", "friction": 0.5}}
    }

A pair's `normal` law and `friction` (a coefficient, or a law with its numbers) come from
the registries of models.contact.laws; each analysis takes the laws it can (a quasi-static
solve the unilateral law, an event_driven simulation the penalty laws, moreau restitution).
A pin in a hole is a circle site on one body and a hole object on another.

An object's pose is numbers (so a sweep, a path or an optimization moves it without
rebuilding anything); with `body` its pose is in that body's axes (from its reference
point) and it moves with the body. Sites are a rigid jaw (a polygon or polyline carried by a
body or by a link's end section, Eq. 6.4) or a link's surface (Eq. 6.5): the side to the left
or right of its centre line, offset by half the local thickness along the cross-section
normal, or the centre line itself.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from flexmech.models.documents.fields import (
    MAX_POINTER_CHARS,
    Expression,
    Name,
    Number,
    OutputName,
    StrictModel,
    Vec2,
)

MAX_VERTICES = 64


class _OnBody(StrictModel):
    body: Name | None = Field(
        default=None, description="the pose is in this body's axes and moves with it (default: fixed, global)"
    )


class CircleObject(_OnBody):
    type: Literal["circle"]
    centre: Vec2
    radius: Number


class HoleObject(_OnBody):
    """A circular hole: the solid is outside the circle (a clearance a pin sits in)."""

    type: Literal["hole"]
    centre: Vec2
    radius: Number


class EllipseObject(_OnBody):
    type: Literal["ellipse"]
    centre: Vec2
    semi_axes: Vec2 = Field(description="along the ellipse's own x and y axes")
    angle: Number = Field(default=0.0, description="of the ellipse's x axis")


class PolygonObject(_OnBody):
    """A simple polygon (convex or not; not self-intersecting), vertices in its own frame,
    placed at `position` turned by `angle`."""

    type: Literal["polygon"]
    vertices: list[Vec2] = Field(min_length=3, max_length=MAX_VERTICES)
    position: Vec2 = (0.0, 0.0)
    angle: Number = 0.0


class HalfPlaneObject(_OnBody):
    """The solid half-plane behind the line through `point`: `normal` points out of it."""

    type: Literal["half_plane"]
    point: Vec2
    normal: Vec2


class ImplicitObject(_OnBody):
    """The solid where g(x, y) < 0: g a safe expression in the object frame's x and y
    (document length units), placed at `position` turned by `angle`; g >= 0 is free space."""

    type: Literal["implicit"]
    expression: Expression
    position: Vec2 = (0.0, 0.0)
    angle: Number = 0.0


ContactObject = Annotated[
    CircleObject | HoleObject | EllipseObject | PolygonObject | HalfPlaneObject | ImplicitObject,
    Field(discriminator="type"),
]
OBJECT_TYPES = ("circle", "hole", "ellipse", "polygon", "half_plane", "implicit")


class JawSite(StrictModel):
    """A rigid jaw: vertices in the frame of a body (its axes from its reference point) or of
    a link's end section (origin on the centre line, x along the tangent)."""

    type: Literal["jaw"]
    body: Name | None = None
    link: Name | None = None
    end: Literal["start", "end"] = Field(default="end", description="which end section of `link` carries it")
    vertices: list[Vec2] = Field(min_length=1, max_length=MAX_VERTICES)
    closed: bool | None = Field(
        default=None, description="a polygon (default with 3 or more vertices) or an open polyline"
    )


class SurfaceSite(StrictModel):
    """A link's surface: `left` or `right` of its centre line (facing from u = 0 to u = 1),
    half the local thickness away along the cross-section normal, or the centre line."""

    type: Literal["surface"]
    link: Name
    side: Literal["left", "right", "centre_line"]


class CircleSite(StrictModel):
    """A circle carried by a body (a pin, a roller), centre in the body's axes from its
    reference point: it touches circles from outside, holes from inside and half-planes."""

    type: Literal["circle"]
    body: Name
    centre: Vec2 = (0.0, 0.0)
    radius: Number


ContactSite = Annotated[JawSite | SurfaceSite | CircleSite, Field(discriminator="type")]
SITE_TYPES = ("jaw", "surface", "circle")


class ComputedStiffness(StrictModel):
    """Hertz's generalized stiffness from geometry and materials: two spheres (Eq. 14, with
    the radius of external contact R1 R2 / (R1 + R2) or of a pin in a hole R1 R2 / (R2 - R1))
    or two cylinders of contact length L (Eq. 16, pi E* L / 4)."""

    contact: Literal["spheres", "cylinders"]
    materials: tuple[Name, Name] = Field(description="the two bodies' materials (E and nu)")
    radius: Literal["external", "conformal"] = Field(
        default="conformal", description="spheres: which effective radius (Table 2 of seed 004 uses external)"
    )
    length: Number | None = Field(default=None, description="cylinders: the contact length")


class NormalLawFields(StrictModel):
    """How the pair pushes: a law of models.contact.laws (unilateral, restitution, hertz,
    hunt_crossley, lankarani_nikravesh, flores, lna_esdu, linear, or one registered) and the
    numbers it reads. Stiffness and damping are in the document's force / length^exponent and
    force s / length unless computed from the materials."""

    law: str = Field(default="unilateral", max_length=64, description="a registered normal law")
    stiffness: Number | ComputedStiffness | None = Field(default=None, description="penalty laws: K, or computed")
    exponent: float = Field(default=1.5, gt=0, le=3, description="n of F = K q^n")
    restitution: float = Field(default=0.9, description="c_r in (0, 1]: the damped laws' damping; moreau's e_N")
    damping: Number | None = Field(default=None, description="linear: the dashpot's c (force s / length)")
    length: Number | None = Field(default=None, description="lna_esdu: the contact length L of Eq. 18")
    materials: tuple[Name, Name] | None = Field(default=None, description="lna_esdu: the two materials (Eq. 18)")


class FrictionFields(StrictModel):
    """A friction law of models.contact.laws: none; coulomb (adherence f_a, sliding f_d;
    quasi-static solves slip at f_d); ambrosio (event_driven: none below v0, f_d from v1)."""

    law: str = Field(default="coulomb", max_length=64, description="a registered friction law")
    sliding: float = Field(default=0.0, description="f_d, the dynamic coefficient")
    adherence: float | None = Field(default=None, description="f_a, the static coefficient (moreau; default f_d)")
    v0: float = Field(default=1e-4, gt=0, description="ambrosio: no friction below this slip speed (m/s)")
    v1: float = Field(default=1e-2, gt=0, description="ambrosio: full friction from this slip speed (m/s)")


class ContactPair(StrictModel):
    site: Name
    object: Name
    normal: NormalLawFields = Field(
        default_factory=NormalLawFields,
        description="the normal law (default: unilateral, the exact contact of quasi-static solves)",
    )
    friction: Number | FrictionFields = Field(default=0.0, description="Coulomb's coefficient mu, or a friction law")

    def friction_pointer(self, base: str) -> str:
        """Where the coefficient a quasi-static solve slips at is: the number, or f_d of a law."""
        return f"{base}/friction" if not isinstance(self.friction, FrictionFields) else f"{base}/friction/sliding"

    def friction_coefficient(self):
        if not isinstance(self.friction, FrictionFields):
            return self.friction
        return 0.0 if self.friction.law == "none" else self.friction.sliding


class PathParameter(StrictModel):
    """A numeric field along the path: its values, or start, stop and equal steps (document units)."""

    path: str = Field(pattern=r"^/", max_length=MAX_POINTER_CHARS)
    values: list[float] | None = Field(default=None, min_length=1)
    start: float | None = None
    stop: float | None = None
    steps: int | None = Field(default=None, ge=1)


class ContactPath(StrictModel):
    """A quasi-static path: every listed field changes together, state after state, each
    solved from the one before (`flexmech contact`, POST /v1/contacts)."""

    parameters: list[PathParameter] = Field(min_length=1, max_length=8)
    outputs: list[OutputName] | None = Field(
        default=None,
        min_length=1,
        max_length=256,
        description="outputs to keep per state (default: every pair's results)",
    )


class Contacts(StrictModel):
    objects: dict[Name, ContactObject] = Field(default={}, max_length=64)
    sites: dict[Name, ContactSite] = Field(default={}, max_length=64)
    pairs: dict[Name, ContactPair] = Field(default={}, max_length=256)
    path: ContactPath | None = None
