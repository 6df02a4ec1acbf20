"""The pin family: a rigid revolute joint between two bodies.

The points of both bodies at `at` stay together: g = r_to(at) - r_from(at) = 0. Outputs: Fx,
Fy, the force body `from` applies to body `to` through the pin (global axes), the relative
rotation of `to` from `from`, and where the pin is (x, y).
"""

from __future__ import annotations

from typing import Literal

import casadi as ca

from flexmech.models.elements.joints import JointFamily, JointTopology, RigidJoint, joint_points


class Pin(RigidJoint):
    """A revolute joint: the bodies turn freely about a common point."""

    type: Literal["pin"]


class PinFamily(JointFamily):
    type = "pin"
    schema = Pin
    constraint_names = ("x", "y")
    multiplier_names = (("lambda_x", "force"), ("lambda_y", "force"))
    impact_labels = (("Fx", "force"), ("Fy", "force"))  # the force the pin applies to `to`

    def impact_rows(self, rb, name, el, first, second, apart) -> ca.SX:
        return apart

    def constraints(self, ctx, t: JointTopology, d) -> ca.SX:
        a, b, _, _ = joint_points(ctx, t, d)
        return b - a

    def joint_outputs(self, ctx, t: JointTopology, d, lam):
        _, b, _, _ = joint_points(ctx, t, d)
        # The `to` body applies lam to the pin, so the pin (and through it `from`) applies -lam to `to`.
        return [
            ("Fx", "force", -lam[0]),
            ("Fy", "force", -lam[1]),
            ("rotation", "angle", d[t.end_body][2] - d[t.start_body][2]),
            ("x", "length", b[0]),
            ("y", "length", b[1]),
        ]


PIN = PinFamily()
