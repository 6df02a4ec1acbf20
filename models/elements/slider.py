"""The slider family: a rigid prismatic joint between two bodies.

Body `to` slides along an axis through `at` at `angle` (global, as drawn) that turns with
body `from`, without turning relative to it: g = [n . (r_to(at) - r_from(at)), theta_to -
theta_from] = 0, n the axis normal (the axis turned by +90 deg). Outputs: N, the force body
`from` applies to `to` along n; M, the couple it applies to `to` to stop it turning; travel,
how far `to` has slid along the axis.
"""

from __future__ import annotations

from typing import Literal

import casadi as ca

from flexmech.models.documents.fields import Number
from flexmech.models.elements.base import Connector
from flexmech.models.elements.joints import JointFamily, JointTopology, RigidJoint, collect_joint, joint_points


class Slider(RigidJoint):
    """A prismatic joint: `to` slides along an axis of `from` without turning."""

    type: Literal["slider"]
    angle: Number = 0.0


def _axis(ctx, t: JointTopology, d) -> tuple[ca.SX, ca.SX]:
    """The axis direction and its normal, turned with body `from`."""
    alpha = ctx.P[f"/elements/{t.name}/angle"] + d[t.start_body][2]
    return ca.vertcat(ca.cos(alpha), ca.sin(alpha)), ca.vertcat(-ca.sin(alpha), ca.cos(alpha))


class SliderFamily(JointFamily):
    type = "slider"
    schema = Slider
    constraint_names = ("normal", "rotation")
    multiplier_names = (("lambda_n", "force"), ("lambda_m", "moment"))
    impact_labels = (("N", "force"), ("M", "moment"))  # across the axis on `to`, and the couple on it

    def connector(self, el: Slider) -> Connector:
        return Connector("slider", (("at", el.to),), angle_field="angle")

    def impact_rows(self, rb, name, el, first, second, apart) -> ca.SX:
        alpha = rb.book.number(f"/elements/{name}/angle", el.angle, "angle") + rb.rotation(first)
        normal = ca.vertcat(-ca.sin(alpha), ca.cos(alpha))
        return ca.vertcat(ca.dot(normal, apart), rb.rotation(second) - rb.rotation(first))

    def collect(self, c, name: str, el: Slider, i: int, j: int) -> JointTopology:
        topology = collect_joint(c, self.type, name, el, i, j)
        c.add(f"/elements/{name}/angle", el.angle, "angle")
        c.holds_rotation(i)
        c.holds_rotation(j)
        return topology

    def constraints(self, ctx, t: JointTopology, d) -> ca.SX:
        a, b, _, _ = joint_points(ctx, t, d)
        _, normal = _axis(ctx, t, d)
        return ca.vertcat(ca.dot(normal, b - a), d[t.end_body][2] - d[t.start_body][2])

    def joint_outputs(self, ctx, t: JointTopology, d, lam):
        a, b, _, _ = joint_points(ctx, t, d)
        direction, _ = _axis(ctx, t, d)
        return [("N", "force", -lam[0]), ("M", "moment", -lam[1]), ("travel", "length", ca.dot(direction, b - a))]


SLIDER = SliderFamily()
