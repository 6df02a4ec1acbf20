"""The spring family: a translational spring between points of two bodies, or a torsional
spring between their rotations, with a linear or a nonlinear law.

Translational: the extension is x = l - rest, l the distance between the points (`from_at`
on body `from`, `to_at` on body `to`: global points of the undeformed mechanism, default
each body's reference point), rest the rest length (default: l as drawn). The force F(x)
is a tension (positive pulls the points together). Torsional: x is the rotation of `to`
relative to `from` from the drawn state less `rest` (default 0); the moment M(x) acts on
`to` as -M and on `from` as +M.

The law is `stiffness` (F = k x), or `law`: a safe expression in x giving F (or M) in the
document's units, x in the document's length (or angle) unit, with named numbers of
`parameters` (numeric fields, so sweeps and optimizations can move them). Its energy is
the integral of the law from 0 to x, by Gauss-Legendre quadrature with QUADRATURE_NODES
nodes: exact for polynomial laws up to degree 2 x QUADRATURE_NODES - 1.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Literal

import casadi as ca
import numpy as np
from pydantic import Field, model_validator

from flexmech.models.documents.expression import CONSTANTS, FUNCTIONS, compile_expression, finite_on
from flexmech.models.documents.fields import MAX_EXPRESSION_CHARS, Name, Number, Vec2
from flexmech.models.elements.base import Connector, Contribution, EnergyTerms, ScaleHint, SiValues, TwoBodyElement
from flexmech.models.errors import MechanismError
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.planar import cross
from flexmech.models.graph.structure import ElementTopology

QUADRATURE_NODES = 24
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(QUADRATURE_NODES)


class Spring(TwoBodyElement):
    """A translational or torsional spring between two bodies (linear: `stiffness`; or a
    `law` in x with named `parameters`)."""

    type: Literal["spring"]
    kind: Literal["translational", "torsional"] = "translational"
    from_at: Vec2 | None = Field(
        default=None, description="translational: the point on `from` (global, undeformed; default its reference point)"
    )
    to_at: Vec2 | None = Field(default=None, description="translational: the point on `to`")
    stiffness: Number | None = Field(default=None, description="force per length, or moment per angle")
    law: str | None = Field(
        default=None,
        max_length=MAX_EXPRESSION_CHARS,
        description="force (moment) as a safe expression in x, the extension (rotation) in document units",
    )
    parameters: dict[Name, Number] = Field(default={}, description="named numbers of the law")
    rest: Number | None = Field(
        default=None,
        description="rest length (translational, default: as drawn) or rest rotation (torsional, default 0)",
    )

    @model_validator(mode="after")
    def _one_law(self):
        if (self.stiffness is None) == (self.law is None):
            raise ValueError("give either 'stiffness' or 'law'")
        if self.kind == "torsional" and (self.from_at is not None or self.to_at is not None):
            raise ValueError("a torsional spring acts between rotations: leave out from_at and to_at")
        return self


@dataclass(frozen=True)
class SpringTopology(ElementTopology):
    kind: str  # translational | torsional
    from_location: str  # at | reference
    to_location: str
    law: str | None  # None: linear
    names: tuple[str, ...]  # the law's named parameters
    rest: bool  # a rest length/rotation is given


class SpringFamily:
    type = "spring"
    schema = Spring

    def connector(self, el: Spring) -> Connector:
        """Drawn between its two points (default: the bodies' reference points)."""
        return Connector("zigzag", (("from_at", el.from_), ("to_at", el.to)), kind=el.kind)

    def collect(self, c, name: str, el: Spring, i: int, j: int) -> SpringTopology:
        base = f"/elements/{name}"
        translational = el.kind == "translational"
        locations = []
        for field_name, body in (("from_at", el.from_), ("to_at", el.to)):
            point = getattr(el, field_name)
            if point is not None and c.doc.bodies[body].joint:
                raise MechanismError(
                    f"{base}/{field_name}",
                    f"a spring attaches to joint '{body}' at the joint itself: leave '{field_name}' out",
                )
            if point is not None:
                c.add_vec(f"{base}/{field_name}", point, "length")
            locations.append("at" if point is not None else "reference")
        deflection = "length" if translational else "angle"
        if el.stiffness is not None:
            c.add(
                f"{base}/stiffness",
                el.stiffness,
                "stiffness" if translational else "rotational_stiffness",
                "nonnegative",
            )
        else:
            _collect_law(c, base, el)
            for kind in (deflection, "force", "length"):  # the law is written in document units
                c.unit_parameter(kind)
        if el.rest is not None:
            c.add(f"{base}/rest", el.rest, deflection, "nonnegative" if translational else None)
        if not translational:
            c.holds_rotation(i)
            c.holds_rotation(j)
        return SpringTopology(
            name, self.type, i, j, el.kind, *locations, el.law, tuple(el.parameters), el.rest is not None
        )

    def contribute(self, ctx: AssemblyContext, t: SpringTopology, d, z) -> Contribution:
        x, geometry = _deflection(ctx, t, d)
        F = _law(ctx, t, x)
        energy = _energy(ctx, t, x)
        i, j = t.start_body, t.end_body
        if t.kind == "torsional":
            return Contribution(
                {i: ca.vertcat(0, 0, -F), j: ca.vertcat(0, 0, F)},
                outputs=[("M", "moment", F), ("rotation", "angle", x), ("energy", "energy", energy)],
                energy=energy,
            )
        a, b, arm_a, arm_b, length = geometry
        pull = F * (b - a) / length  # the force body `to` applies to the spring at b (tension: away from a)
        return Contribution(
            {i: ca.vertcat(-pull, cross(arm_a, -pull)), j: ca.vertcat(pull, cross(arm_b, pull))},
            outputs=[
                ("F", "force", F),
                ("extension", "length", x),
                ("length", "length", length),
                ("energy", "energy", energy),
            ],
            energy=energy,
        )

    def unknowns(self, t: SpringTopology) -> list[tuple[str, str]]:
        return []

    def energy_terms(self, ctx: AssemblyContext, t: SpringTopology, d) -> EnergyTerms:
        x, _ = _deflection(ctx, t, d)
        return EnergyTerms(_energy(ctx, t, x))

    def kinetic_energy(self, ctx, t: SpringTopology, d, v) -> None:
        return None  # massless

    def scale_hint(self, t: SpringTopology, values: SiValues) -> ScaleHint:
        k = values[f"/elements/{t.name}/stiffness"] if f"/elements/{t.name}/stiffness" in values else None
        if t.kind == "torsional":
            return ScaleHint(rotational_stiffness=k)
        return ScaleHint(stiffness=k)


def _collect_law(c, base: str, el: Spring) -> None:
    reserved = {"x", *CONSTANTS, *FUNCTIONS}
    env = {}
    for key, value in el.parameters.items():
        if not key.isidentifier() or key in reserved:
            raise MechanismError(
                f"{base}/parameters/{key}",
                f"'{key}' cannot name a parameter (use a name like k3, not x, pi, e or a function name)",
            )
        c.add(f"{base}/parameters/{key}", value, "dimensionless")
        env[key] = c.values[-1]
    build = compile_expression(el.law, f"{base}/law", "x", tuple(el.parameters))
    finite_on(build, f"{base}/law", (0.0,), "x", env)  # the drawn state is unloaded: F(0) must be a number


def _deflection(ctx: AssemblyContext, t: SpringTopology, d):
    """The extension (rotation) x, nondimensional, and for a translational spring its
    geometry: both points, their arms from the reference points, and the length."""
    base = f"/elements/{t.name}"
    i, j = t.start_body, t.end_body
    if t.kind == "torsional":
        x = d[j][2] - d[i][2]
        return (x - ctx.P[f"{base}/rest"] if t.rest else x), None
    local_a = ctx.local_point(i, base, t.from_location, "from_at")
    local_b = ctx.local_point(j, base, t.to_location, "to_at")
    zero = [ca.SX.zeros(3) for _ in range(ctx.n_bodies)]
    a, b = ctx.place(i, local_a, d), ctx.place(j, local_b, d)
    length = ca.norm_2(b - a)
    rest = ctx.P[f"{base}/rest"] if t.rest else ca.norm_2(ctx.place(j, local_b, zero) - ctx.place(i, local_a, zero))
    return length - rest, (a, b, ctx.arm(i, local_a, d), ctx.arm(j, local_b, d), length)


@lru_cache(maxsize=256)
def _compiled(law: str, pointer: str, names: tuple[str, ...]):
    return compile_expression(law, pointer, "x", names)


def _law(ctx: AssemblyContext, t: SpringTopology, x):
    """The force (moment) at the nondimensional deflection x, nondimensional."""
    base = f"/elements/{t.name}"
    if t.law is None:
        return ctx.P[f"{base}/stiffness"] * x
    length_kind, force_kind = ("length", "force") if t.kind == "translational" else ("angle", "moment")
    build = _compiled(t.law, f"{base}/law", t.names)
    env = {name: ctx.P[f"{base}/parameters/{name}"] for name in t.names}
    return ca.SX(build(x / ctx.unit(length_kind), env)) * ctx.unit(force_kind)


def _energy(ctx: AssemblyContext, t: SpringTopology, x):
    """The integral of the law from 0 to x (exact for the linear law)."""
    if t.law is None:
        return 0.5 * ctx.P[f"/elements/{t.name}/stiffness"] * x**2
    total = ca.SX(0)
    for node, weight in zip(_NODES, _WEIGHTS):
        total = total + weight * _law(ctx, t, x * (node + 1) / 2)
    return total * x / 2


SPRING = SpringFamily()
