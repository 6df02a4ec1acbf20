"""Cross-sections: their document schema, the parameters they contribute, and their symbolic
properties along an element (u from 0 to 1).

Rectangles have width b (out of the plane of motion) and thickness h (in the plane, the
bending direction); tapered rectangles vary h linearly from h_start (u = 0) to h_end; general
sections give I and A as numbers or safe expressions in u, in the document's length unit to
the fourth and second power, and c (the outer-fibre distance) for stresses.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated, Literal

import casadi as ca
from pydantic import Discriminator, Field, Tag

from flexmech.models.documents.expression import compile_expression, finite_on
from flexmech.models.documents.fields import Expression, Number, StrictModel

if TYPE_CHECKING:
    from flexmech.models.graph.collector import Collector
    from flexmech.models.graph.context import Params


class RectangularSection(StrictModel):
    shape: Literal["rectangle"] = "rectangle"
    b: Number = Field(description="width, out of the plane of motion")
    h: Number = Field(description="thickness, in the plane of motion (the bending direction)")
    shear_factor: Number | None = Field(default=None, description="Timoshenko kappa (default 5/6)")


class TaperedRectangularSection(StrictModel):
    """A rectangle whose thickness varies linearly along a link, from h_start (u = 0) to h_end."""

    shape: Literal["tapered_rectangle"]
    b: Number
    h_start: Number
    h_end: Number
    shear_factor: Number | None = None


class SectionExpression(StrictModel):
    expression: Expression = Field(description="safe math expression in u (0..1 along the link)")


class GeneralSection(StrictModel):
    """Second moment I and area A, each a number or an expression in u, in the document's
    length unit to the fourth and second power."""

    shape: Literal["general"]
    I: Number | SectionExpression
    A: Number | SectionExpression | None = None
    shear_factor: Number | None = None
    c: Number | None = Field(
        default=None, description="distance from the neutral axis to the outer fibre, for stresses"
    )


def _section_shape(value) -> str:
    if isinstance(value, dict):
        return value.get("shape", "rectangle")
    return getattr(value, "shape", "rectangle")


Section = Annotated[
    Annotated[RectangularSection, Tag("rectangle")]
    | Annotated[TaperedRectangularSection, Tag("tapered_rectangle")]
    | Annotated[GeneralSection, Tag("general")],
    Discriminator(_section_shape),
]


ALONG = tuple(k / 16 for k in range(17))  # where a section expression must be positive


@dataclass(frozen=True)
class SectionTopology:
    """What of a section shapes the graphs: its name, shape and expressions (no numbers)."""

    name: str
    shape: str  # rectangle | tapered_rectangle | general
    I_expression: str | None = None
    A_expression: str | None = None


def section_topology(name: str, section) -> SectionTopology:
    if isinstance(section, GeneralSection):
        I_expr = section.I.expression if isinstance(section.I, SectionExpression) else None
        A_expr = section.A.expression if isinstance(section.A, SectionExpression) else None
        return SectionTopology(name, "general", I_expr, A_expr)
    return SectionTopology(name, section.shape)


def collect_section(c: Collector, name: str, section, needs_area: bool) -> None:
    """Add a used section's numbers to the parameters (checked: positive)."""
    base = f"/sections/{name}"
    if isinstance(section, RectangularSection):
        c.add(f"{base}/b", section.b, "length", "positive")
        c.add(f"{base}/h", section.h, "length", "positive")
    elif isinstance(section, TaperedRectangularSection):
        c.add(f"{base}/b", section.b, "length", "positive")
        c.add(f"{base}/h_start", section.h_start, "length", "positive")
        c.add(f"{base}/h_end", section.h_end, "length", "positive")
    else:
        for field_name, kind in (("I", "second_moment"), ("A", "area")):
            value = getattr(section, field_name)
            if isinstance(value, SectionExpression):
                pointer = f"{base}/{field_name}/expression"
                finite_on(compile_expression(value.expression, pointer), pointer, ALONG, positive=True)
                c.unit_parameter("length")  # expressions are in document length units
            elif value is not None:
                c.add(f"{base}/{field_name}", value, kind, "positive")
        if section.c is not None:
            c.add(f"{base}/c", section.c, "length", "positive")
    if section.shear_factor is not None:
        c.add(f"{base}/shear_factor", section.shear_factor, "dimensionless", "positive")


@dataclass(frozen=True)
class SectionProperties:
    """Nondimensional builders over u: I, A (None when not given), the stress factor c / I
    (None when the outer fibre is unknown) and the half thickness (None when unknown)."""

    I: Callable[[ca.SX], ca.SX]
    A: Callable[[ca.SX], ca.SX] | None
    fibre: Callable[[ca.SX], ca.SX] | None
    half_thickness: Callable[[ca.SX], ca.SX] | None


def section_properties(P: Params, section: SectionTopology) -> SectionProperties:
    base = f"/sections/{section.name}"
    if section.shape in ("rectangle", "tapered_rectangle"):
        b = P[f"{base}/b"]
        if section.shape == "rectangle":
            thickness = lambda u: P[f"{base}/h"] + 0 * u  # noqa: E731
        else:
            h0, h1 = P[f"{base}/h_start"], P[f"{base}/h_end"]
            thickness = lambda u: h0 + (h1 - h0) * u  # noqa: E731
        return SectionProperties(
            I=lambda u: b * thickness(u) ** 3 / 12,
            A=lambda u: b * thickness(u),
            fibre=lambda u: 6 / (b * thickness(u) ** 2),
            half_thickness=lambda u: thickness(u) / 2,
        )
    # General: numbers are parameters; expressions are in document length units, and the
    # parameter /units/length is one document length unit (nondimensional).
    to_nd = P["/units/length"] if "/units/length" in P else 1.0

    def field(name: str, power: int, expression: str | None):
        if expression is not None:
            build = compile_expression(expression, f"{base}/{name}/expression")
            return lambda u: ca.SX(build(u)) * to_nd**power
        if f"{base}/{name}" in P:
            value = P[f"{base}/{name}"]
            return lambda u: value + 0 * u
        return None

    I = field("I", 4, section.I_expression)
    A = field("A", 2, section.A_expression)
    fibre = half = None
    if f"{base}/c" in P:
        c = P[f"{base}/c"]
        fibre = lambda u: c / I(u)  # noqa: E731
        half = lambda u: c + 0 * u  # noqa: E731
    return SectionProperties(I, A, fibre, half)


def nominal_EI(values: dict[str, float], section: SectionTopology, E: float, length_unit_si: float) -> float:
    """E times a representative I of a section (SI): its largest along a taper, mid-length for
    an expression. For scaling only. `values` maps pointers to SI values."""
    base = f"/sections/{section.name}"
    if section.shape == "rectangle":
        return E * values[f"{base}/b"] * values[f"{base}/h"] ** 3 / 12
    if section.shape == "tapered_rectangle":
        h = max(values[f"{base}/h_start"], values[f"{base}/h_end"])
        return E * values[f"{base}/b"] * h**3 / 12
    if f"{base}/I" in values:
        return E * values[f"{base}/I"]
    u = ca.SX.sym("u")
    at_middle = float(ca.Function("I", [u], [ca.SX(compile_expression(section.I_expression, "")(u))])(0.5))
    return E * at_middle * length_unit_si**4  # the expression is in document length units ^ 4
