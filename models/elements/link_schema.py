"""The link's section of a mechanism document: the link (Lan 2005) and the shapes of its
unloaded centre line (the tangent angle eta(u))."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from flexmech.models.documents.fields import Expression, Name, Number, StrictModel, Vec2
from flexmech.models.elements.base import TwoBodyElement


class StraightShape(StrictModel):
    type: Literal["straight"]
    angle: Number = Field(default=0.0, description="direction from the start point")


class ArcShape(StrictModel):
    """eta(u) = angle + sweep * u: a circular arc of radius length / |sweep|."""

    type: Literal["arc"]
    angle: Number = 0.0
    sweep: Number


class PolynomialShape(StrictModel):
    """eta(u) = sum coefficients[k] * u**k, in radians."""

    type: Literal["polynomial"]
    coefficients: list[Number] = Field(min_length=1, max_length=32)


class FourierSineShape(StrictModel):
    """eta(u) = angle + sum over i = 1.. of coefficients[i-1] * sin(i * omega * u); the
    coefficients in radians, omega (default 2 pi, as in Lan 2005 Sec. 5.6) in rad."""

    type: Literal["fourier_sine"]
    angle: Number = 0.0
    coefficients: list[Number] = Field(min_length=1, max_length=32)
    omega: float = 2 * 3.141592653589793


class ExpressionShape(StrictModel):
    """eta(u), radians, as a safe math expression in u."""

    type: Literal["expression"]
    expression: Expression


Shape = StraightShape | ArcShape | PolynomialShape | FourierSineShape | ExpressionShape
SHAPE_TYPES = ("straight", "arc", "polynomial", "fourier_sine", "expression")


class Link(TwoBodyElement):
    """A distributed elastica (Lan 2005) from body `from` (u = 0) to body `to` (u = 1).

    It starts at `at` (default: the `from` body's reference point) with the initial tangent
    angle eta(u) of `shape` (global frame) and ends where that shape ends; both ends are
    attached to their bodies there, clamped or pinned.
    """

    type: Literal["link"]
    at: Vec2 | None = None
    length: Number
    shape: Shape = Field(default=StraightShape(type="straight"), discriminator="type")
    material: Name
    section: Name
    start: Literal["clamped", "pinned"] = "clamped"
    end: Literal["clamped", "pinned"] = "clamped"
    shear: bool = Field(default=False, description="Timoshenko shear strain (Lan 2005 Eq. 5.1)")
    axial: bool = Field(default=False, description="axial strain (Lan 2005 App. A.1)")
    discretization: Literal["shooting", "elements"] = Field(
        default="shooting",
        description="multiple shooting (mixes forces and displacements), or displacement-based "
        "elements (an energy: needed for minimum energy and contact)",
    )
    intervals: int = Field(default=8, ge=1, le=128, description="shooting intervals, or elements")
    order: int = Field(
        default=8, ge=2, le=12, description="shooting: integration order (even), 2 x extrapolation levels"
    )
    degree: int = Field(default=3, ge=1, le=6, description="elements: polynomial degree of the rotation")
