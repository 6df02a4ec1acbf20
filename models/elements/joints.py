"""Rigid joints between two bodies: the shared part of the pin and slider families.

A joint holds two constraints g(d) = 0 between points of its bodies that coincide in the
drawn mechanism (at `at`, global; default the `to` body's reference point). Its unknowns are
their multipliers lam; the wrench each body applies to the joint is (dg/dd_b)^T lam, and its
rows are g (models.elements.base). The energy form states g as equalities whose multipliers
are the same lam.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import casadi as ca
from pydantic import Field

from flexmech.models.documents.fields import Vec2
from flexmech.models.elements.base import (
    Connector,
    Contribution,
    EnergyTerms,
    ScaleHint,
    SiValues,
    TwoBodyElement,
    constraint_wrenches,
)
from flexmech.models.errors import MechanismError
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.structure import ElementTopology


class RigidJoint(TwoBodyElement):
    at: Vec2 | None = Field(
        default=None, description="where the joint is (global, undeformed; default: the `to` body's reference point)"
    )


@dataclass(frozen=True)
class JointTopology(ElementTopology):
    located: str  # at | reference

    @property
    def unknowns(self) -> int:
        return 2


def collect_joint(c, family: str, name: str, el: RigidJoint, i: int, j: int) -> JointTopology:
    if el.at is not None:
        c.add_vec(f"/elements/{name}/at", el.at, "length")
    return JointTopology(name, family, i, j, "at" if el.at is not None else "reference")


def joint_points(ctx: AssemblyContext, t: JointTopology, d: list[ca.SX]):
    """The joint's point on each body (global) and their arms from the reference points."""
    point = ctx.P.vec(f"/elements/{t.name}/at") if t.located == "at" else ctx.reference(t.end_body)[0]
    i, j = t.start_body, t.end_body
    local_a, local_b = ctx.body_axes(i, point), ctx.body_axes(j, point)
    return ctx.place(i, local_a, d), ctx.place(j, local_b, d), ctx.arm(i, local_a, d), ctx.arm(j, local_b, d)


class JointFamily(ABC):
    """A family of rigid joints given by its constraints g(d) and its outputs."""

    type: str
    schema: type[RigidJoint]
    constraint_names: tuple[str, str]
    multiplier_names: tuple[tuple[str, str], tuple[str, str]]  # (name, kind) of lam

    @abstractmethod
    def constraints(self, ctx: AssemblyContext, t: JointTopology, d: list[ca.SX]) -> ca.SX:
        """g(d): two rows, zero where the joint holds."""

    @abstractmethod
    def joint_outputs(self, ctx: AssemblyContext, t: JointTopology, d, lam) -> list[tuple[str, str, ca.SX]]:
        """(name, kind, value) of its reported quantities."""

    def collect(self, c, name: str, el: RigidJoint, i: int, j: int) -> JointTopology:
        return collect_joint(c, self.type, name, el, i, j)

    def contribute(self, ctx: AssemblyContext, t: JointTopology, d, z) -> Contribution:
        wrenches = constraint_wrenches(
            ctx, (t.start_body, t.end_body), d, z, lambda local: self.constraints(ctx, t, local)
        )
        return Contribution(wrenches, self.constraints(ctx, t, d), self.joint_outputs(ctx, t, d, z))

    def unknowns(self, t: JointTopology) -> list[tuple[str, str]]:
        return list(self.multiplier_names)

    def energy_terms(self, ctx: AssemblyContext, t: JointTopology, d) -> EnergyTerms:
        g = self.constraints(ctx, t, d)
        return EnergyTerms(ca.SX(0), equalities=[(name, g[k]) for k, name in enumerate(self.constraint_names)])

    def kinetic_energy(self, ctx: AssemblyContext, t: JointTopology, d, v) -> None:
        return None  # massless: the bodies carry the mass

    def scale_hint(self, t: JointTopology, values: SiValues) -> ScaleHint:
        return ScaleHint()

    def connector(self, el: RigidJoint) -> Connector:
        """Drawn at its joint point `at` (default: the `to` body's reference point)."""
        return Connector("pin", (("at", el.to),))

    impact_labels: tuple[tuple[str, str], tuple[str, str]] = ()  # (label, kind) of an impact model's multipliers

    def impact_constraint(self, rb, name: str, el: RigidJoint) -> tuple[ca.SX, tuple]:
        """In an impact simulation (models.impacts): (g(q), the multipliers' labels), from the
        joint point `at` (global in the drawn pose; default the `to` body's reference point)
        carried by each body."""
        base = f"/elements/{name}"
        first, second = rb.body(el.from_, f"{base}/from"), rb.body(el.to, f"{base}/to")
        at = rb.book.vector(f"{base}/at", el.at, "length") if el.at is not None else second.position
        apart = rb.drawn_point(second, at) - rb.drawn_point(first, at)
        return self.impact_rows(rb, name, el, first, second, apart), self.impact_labels

    def impact_rows(self, rb, name: str, el: RigidJoint, first, second, apart: ca.SX) -> ca.SX:
        """g(q) of an impact model from `apart`, the joint point on `to` less that on `from`."""
        raise MechanismError(f"/elements/{name}/type", f"{self.type} joints are not part of impact simulations")
