"""The `contacts` section of a mechanism document: rigid objects, contact sites, and pairs.

    "contacts": {
      "objects": {"fixture": {"type": "circle", "centre": [78, 10.5], "radius": 8.9}},
      "sites":   {"jaw": {"type": "jaw", "body": "tip", "vertices": [[0, 0], [19, 1.6], [0, 10.46]]}},
      "pairs":   {"grip": {"site": "jaw", "object": "fixture", "friction": 0.5}}
    }

An object's pose is numbers (so a sweep, a path or an optimization moves it without
rebuilding anything); with `body` its pose is in that body's axes (from its reference
point) and it moves with the body. Sites are a rigid jaw (a polygon or polyline carried by a
body or by a link's end section, Eq. 6.4) or a link's surface (Eq. 6.5): the side to the left
or right of its centre line, offset by half the local thickness along the cross-section
normal, or the centre line itself.
"""

from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import Field

from models.fields import Number, StrictModel, Vec2

MAX_VERTICES = 64


class _OnBody(StrictModel):
    body: str | None = Field(default=None, description="the pose is in this body's axes and moves with it "
                             "(default: fixed, global)")


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
    expression: str
    position: Vec2 = (0.0, 0.0)
    angle: Number = 0.0


ContactObject = Annotated[Union[CircleObject, HoleObject, EllipseObject, PolygonObject, HalfPlaneObject,
                                ImplicitObject], Field(discriminator="type")]
OBJECT_TYPES = ("circle", "hole", "ellipse", "polygon", "half_plane", "implicit")


class JawSite(StrictModel):
    """A rigid jaw: vertices in the frame of a body (its axes from its reference point) or of
    a link's end section (origin on the centre line, x along the tangent)."""

    type: Literal["jaw"]
    body: str | None = None
    link: str | None = None
    end: Literal["start", "end"] = Field(default="end", description="which end section of `link` carries it")
    vertices: list[Vec2] = Field(min_length=1, max_length=MAX_VERTICES)
    closed: bool | None = Field(default=None, description="a polygon (default with 3 or more vertices) or an "
                                "open polyline")


class SurfaceSite(StrictModel):
    """A link's surface: `left` or `right` of its centre line (facing from u = 0 to u = 1),
    half the local thickness away along the cross-section normal, or the centre line."""

    type: Literal["surface"]
    link: str
    side: Literal["left", "right", "centre_line"]


class CircleSite(StrictModel):
    """A circle carried by a body (a pin, a roller), centre in the body's axes from its
    reference point: it touches circles from outside, holes from inside and half-planes."""

    type: Literal["circle"]
    body: str
    centre: Vec2 = (0.0, 0.0)
    radius: Number


ContactSite = Annotated[Union[JawSite, SurfaceSite, CircleSite], Field(discriminator="type")]
SITE_TYPES = ("jaw", "surface", "circle")


class ContactPair(StrictModel):
    site: str
    object: str
    friction: Number = Field(default=0.0, description="Coulomb's coefficient mu")


class PathParameter(StrictModel):
    """A numeric field along the path: its values, or start, stop and equal steps (document units)."""

    path: str = Field(pattern=r"^/", max_length=256)
    values: list[float] | None = Field(default=None, min_length=1)
    start: float | None = None
    stop: float | None = None
    steps: int | None = Field(default=None, ge=1)


class ContactPath(StrictModel):
    """A quasi-static path: every listed field changes together, state after state, each
    solved from the one before (`flexmech contact`, POST /v1/contacts)."""

    parameters: list[PathParameter] = Field(min_length=1, max_length=8)
    outputs: list[str] | None = Field(default=None, min_length=1, max_length=256,
                                      description="outputs to keep per state (default: every pair's results)")


class Contacts(StrictModel):
    objects: dict[str, ContactObject] = Field(default={}, max_length=64)
    sites: dict[str, ContactSite] = Field(default={}, max_length=64)
    pairs: dict[str, ContactPair] = Field(default={}, max_length=256)
    path: ContactPath | None = None
