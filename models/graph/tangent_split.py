"""The split of the tangent stiffness of seed 000 (Eqs. 26-28), for structures with
curved-beam flexures, built on demand.

K_T = dR/dz is differentiated through separate copies of z: term I through the flexures'
deformation psi (and every other element wholly, links included: their unknowns enter the
balance as the flexures' psi does), II through the body rotations carrying the flexures'
attachments (N), III through the tip displacement in T'_f (the partial non-linear model),
and a load term through the arms of forces applied off the reference point (zero in the
paper, whose loads sit at mass centres). The four sum to K_T.
"""

from __future__ import annotations

import casadi as ca

from flexmech.models.elements import FAMILIES
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.loads import applied_wrenches
from flexmech.models.graph.residual import residual_of
from flexmech.models.graph.structure import Structure

TERMS = ("psi", "N", "T", "load")


def tangent_terms(structure: Structure) -> ca.Function:
    """(z, p) -> (K_I, K_II, K_III, K_load)."""
    ctx = AssemblyContext(structure)
    n = structure.n_unknowns
    z = ca.SX.sym("z", n)
    copies = {k: ca.SX.sym(f"z_{k}", n) for k in TERMS}
    d = {k: ctx.displacements(v) for k, v in copies.items()}
    parts = []
    for t, offset in zip(structure.elements, structure.element_offsets):
        split = getattr(FAMILIES.of(t), "split_contribution", None)
        if split is not None:
            parts.append(split(ctx, t, d["psi"], d["N"], d["T"]))
        else:
            parts.append(FAMILIES.of(t).contribute(ctx, t, d["psi"], copies["psi"][offset : offset + t.unknowns]))
    R = residual_of(ctx, parts, applied_wrenches(ctx, d["load"]))
    every = ca.vertcat(*copies.values())
    same = ca.vertcat(*[z] * len(TERMS))
    terms = [ca.substitute(ca.jacobian(R, copies[k]), every, same) for k in TERMS]
    fn = ca.Function("tangent_terms", [z, ctx.p], terms, ["z", "p"], ["K_I", "K_II", "K_III", "K_load"], dict(cse=True))
    if fn.has_free():
        raise RuntimeError(f"graph {fn.name()} has free symbols {fn.get_free()}")
    return fn
