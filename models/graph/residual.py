"""The pieces of the residual form that every graph builder shares: the elements'
contributions, the wrench each body applies to its elements, and the rows of free
coordinates."""

from __future__ import annotations

from dataclasses import replace

import casadi as ca

from flexmech.models.elements import FAMILIES
from flexmech.models.elements.base import Contribution
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.structure import Structure


def contributions(ctx: AssemblyContext, z: ca.SX, d: list[ca.SX]) -> list[Contribution]:
    """Every element's contribution for unknowns z and body displacements d, merged."""
    s = ctx.structure
    return [
        merged(FAMILIES.of(t).contribute(ctx, t, d, z[offset : offset + t.unknowns]))
        for t, offset in zip(s.elements, s.element_offsets)
    ]


def merged(part: Contribution) -> Contribution:
    """The part with the common subexpressions of its wrenches and rows merged, before anything
    differentiates them (a curved beam's compliance, a link element's angle: 10-40% of their
    residual). A part that says it is merged already is kept: CasADi's cse costs a few
    microseconds a node, 0.1-0.17 s of a large structure of links, to merge 0.1% of it."""
    if part.merged:
        return part
    pieces = [*part.from_bodies.values(), *([part.rows] if part.rows is not None else [])]
    if not pieces:
        return part
    sizes = [0]
    for piece in pieces:
        sizes.append(sizes[-1] + piece.numel())
    out = ca.vertsplit(ca.cse(ca.vertcat(*pieces)), sizes)
    bodies = dict(zip(part.from_bodies, out))
    rows = out[-1] if part.rows is not None else None
    return replace(part, from_bodies=bodies, rows=rows, merged=True)


def unknown_names(structure: Structure) -> list[tuple[str, str]]:
    """(name, kind) of every entry of z: the free body coordinates ("tip.x", length or angle),
    then each element's own unknowns ("L1.h", "L1.node3.psi", ...)."""
    kinds = ("length", "length", "angle")
    names = [(structure.coordinate_name(b, c), kinds[c]) for b, c in structure.free]
    for t in structure.elements:
        names += [(f"{t.name}.{name}", kind) for name, kind in FAMILIES.of(t).unknowns(t)]
    return names


def held_wrenches(ctx: AssemblyContext, parts: list[Contribution]) -> list[ca.SX]:
    """Per body, the wrench it applies to all its elements."""
    held = [ca.SX.zeros(3) for _ in range(ctx.n_bodies)]
    for part in parts:
        for b, wrench in part.from_bodies.items():
            held[b] = held[b] + wrench
    return held


def free_rows(structure: Structure, per_body: list[ca.SX]) -> ca.SX:
    return ca.vertcat(*[per_body[b][c] for b, c in structure.free]) if structure.free else ca.SX(0, 1)


def residual_of(ctx: AssemblyContext, parts: list[Contribution], applied: list[ca.SX]) -> ca.SX:
    """Free body rows (held - applied), then every element's own rows."""
    held = held_wrenches(ctx, parts)
    rows = [part.rows for part in parts if part.rows is not None]
    return ca.vertcat(free_rows(ctx.structure, [held[b] - applied[b] for b in range(ctx.n_bodies)]), *rows)
