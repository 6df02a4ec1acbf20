"""What an element family sees while the graphs of a structure are built: the symbolic
parameter vector (by JSON pointer), the bodies' reference poses, and points on bodies.

Body displacements d[b] = [dx, dy, dangle] (nondimensional) are taken from the undeformed
pose; a point given in body axes (from the reference point) sits at r_hat + d[:2] +
rot(theta_hat + d[2]) @ local.
"""

from __future__ import annotations

import casadi as ca

from flexmech.models.graph.planar import rot
from flexmech.models.graph.structure import Structure


class Params:
    """The parameter vector p (SX), indexed by the JSON pointers of the document's fields."""

    def __init__(self, structure: Structure, p: ca.SX):
        self.index = structure.index
        self.p = p

    def __getitem__(self, pointer: str) -> ca.SX:
        return self.p[self.index[pointer]]

    def __contains__(self, pointer: str) -> bool:
        return pointer in self.index

    def vec(self, pointer: str) -> ca.SX:
        return ca.vertcat(self[f"{pointer}/0"], self[f"{pointer}/1"])


class AssemblyContext:
    def __init__(self, structure: Structure, p: ca.SX | None = None):
        self.structure = structure
        self.p = ca.SX.sym("p", len(structure.parameters)) if p is None else p
        self.P = Params(structure, self.p)
        self.n_bodies = len(structure.bodies)

    def reference(self, b: int) -> tuple[ca.SX, ca.SX]:
        """Undeformed reference point (2,) and angle of body b."""
        name = self.structure.bodies[b]
        return self.P.vec(f"/bodies/{name}/position"), self.P[f"/bodies/{name}/angle"]

    def local_point(self, b: int, base: str, location: str, field: str = "") -> ca.SX:
        """A point of body b in body axes, from the reference point: `location` "offset" (the
        field {base}/offset), "at" (a global undeformed point, {base}/at) or "reference".
        `field` renames the field (e.g. from_at)."""
        if location == "offset":
            return self.P.vec(f"{base}/{field or 'offset'}")
        if location == "at":
            r_hat, th_hat = self.reference(b)
            return rot(th_hat).T @ (self.P.vec(f"{base}/{field or 'at'}") - r_hat)
        return ca.SX.zeros(2)

    def body_axes(self, b: int, point: ca.SX) -> ca.SX:
        """A global undeformed point (or 2 x n points) in body b's axes, from its reference point."""
        r_hat, th_hat = self.reference(b)
        return rot(th_hat).T @ (point - _spread(r_hat, point))

    def place(self, b: int, local: ca.SX, d: list[ca.SX]) -> ca.SX:
        """Global position of a point (or 2 x n points) of body b (body axes `local`) for
        displacements d."""
        r_hat, th_hat = self.reference(b)
        return _spread(r_hat + d[b][:2], local) + rot(th_hat + d[b][2]) @ local

    def arm(self, b: int, local: ca.SX, d: list[ca.SX]) -> ca.SX:
        """From body b's displaced reference point to its point `local`, global axes."""
        return rot(self.reference(b)[1] + d[b][2]) @ local

    def unit(self, kind: str) -> ca.SX:
        """One document unit of `kind` (length, force, angle, moment), nondimensional: the
        parameters /units/<kind> a family asked the collector for."""
        if kind == "moment":
            return self.unit("force") * self.unit("length")
        return self.P[f"/units/{kind}"]

    def displacements(self, z: ca.SX) -> list[ca.SX]:
        """Displacement [dx, dy, dangle] of every body: free ones from z, prescribed ones
        from their parameters (0 for fixed)."""
        free_index = {bc: k for k, bc in enumerate(self.structure.free)}
        out = []
        for b, row in enumerate(self.structure.prescribed):
            comps = []
            for c in range(3):
                if row[c] is None:
                    comps.append(z[free_index[(b, c)]])
                elif row[c] == "":
                    comps.append(ca.SX(0))
                else:
                    comps.append(self.P[row[c]])
            out.append(ca.vertcat(*comps))
        return out


def _spread(column: ca.SX, like) -> ca.SX:
    """column repeated over like's columns (a point, or 2 x n points); itself for one."""
    n = like.shape[1] if len(getattr(like, "shape", ())) == 2 else 1
    return column if n == 1 else ca.repmat(column, 1, n)
