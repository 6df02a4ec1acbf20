"""The named outputs of a structure and its centre-line samples, as Functions of (z, p).

Outputs (nondimensional; kinds give their units): bodies.<b>.x|y|angle, reactions.<b>.Fx|Fy|M
of supported bodies, elements.<e>.<quantity> as each family names them, the total strain
energy, and the document's point and reaction outputs.
"""

from __future__ import annotations

import casadi as ca

from flexmech.models.contact.elastic_pairs import contact_outputs
from flexmech.models.elements.base import Contribution
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.residual import held_wrenches

REACTION_QUANTITIES = (("Fx", "force"), ("Fy", "force"), ("M", "moment"))


def output_graph(
    ctx: AssemblyContext, z: ca.SX, d: list[ca.SX], parts: list[Contribution], applied: list[ca.SX]
) -> tuple[ca.Function, list[str], list[str]]:
    s = ctx.structure
    names: list[str] = []
    kinds: list[str] = []
    values: list[ca.SX] = []

    def emit(name, kind, value):
        names.append(name)
        kinds.append(kind)
        values.append(value)

    for b, body in enumerate(s.bodies):
        r_hat, th_hat = ctx.reference(b)
        emit(f"bodies.{body}.x", "length", r_hat[0] + d[b][0])
        emit(f"bodies.{body}.y", "length", r_hat[1] + d[b][1])
        emit(f"bodies.{body}.angle", "angle", th_hat + d[b][2])
    held = held_wrenches(ctx, parts)
    # Equilibrium: applied + support - held = 0, so the support supplies held - applied.
    reaction = [held[b] - applied[b] for b in range(ctx.n_bodies)]
    for b, body in enumerate(s.bodies):
        if any(v is not None for v in s.prescribed[b]):
            for c, (q, kind) in enumerate(REACTION_QUANTITIES):
                emit(f"reactions.{body}.{q}", kind, reaction[b][c])
    energy = ca.SX(0)
    for t, part in zip(s.elements, parts):
        for quantity, kind, value in part.outputs:
            emit(f"elements.{t.name}.{quantity}", kind, value)
        if part.energy is not None:
            energy = energy + part.energy
    emit("energy", "energy", energy)
    for name, kind, value in contact_outputs(ctx, d):  # the elastic contact pairs
        emit(name, kind, value)
    zero = [ca.SX.zeros(3) for _ in range(ctx.n_bodies)]
    for pt in s.points:
        local = ctx.local_point(pt.body, f"/outputs/{pt.name}", pt.location)
        here, there = ctx.place(pt.body, local, d), ctx.place(pt.body, local, zero)
        emit(f"{pt.name}.x", "length", here[0])
        emit(f"{pt.name}.y", "length", here[1])
        emit(f"{pt.name}.dx", "length", here[0] - there[0])
        emit(f"{pt.name}.dy", "length", here[1] - there[1])
    for name, b in s.reactions:
        for c, (q, kind) in enumerate(REACTION_QUANTITIES):
            emit(f"{name}.{q}", kind, reaction[b][c])
    # no common-subexpression pass: it took 0.5-0.6 s of a large structure's first solve (six_bar,
    # gripper_exact) to save 0.15-0.2 ms of each evaluation, and outputs are evaluated once a state
    outputs = ca.Function("outputs", [z, ctx.p], [ca.vertcat(*values)], ["z", "p"], ["y"])
    return outputs, names, kinds


def shape_graph(ctx: AssemblyContext, z: ca.SX, parts: list[Contribution]):
    """(z, p) -> (deformed, undeformed): 2 x (samples of every element drawn), and per element
    drawn (name, first column, columns, start body, end body)."""
    deformed, undeformed, segments = [], [], []
    for t, part in zip(ctx.structure.elements, parts):
        line = part.centre_line
        if line is None:
            continue
        segments.append((t.name, len(deformed), len(line.deformed), t.start_body, t.end_body))
        deformed.extend(line.deformed)
        undeformed.extend(line.undeformed)
    if not deformed:
        deformed = undeformed = [ca.SX.zeros(2, 0)]
    shapes = ca.Function(
        "shapes", [z, ctx.p], [ca.horzcat(*deformed), ca.horzcat(*undeformed)], ["z", "p"], ["deformed", "undeformed"]
    )
    return shapes, segments
