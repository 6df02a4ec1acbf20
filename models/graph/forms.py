"""The other problem forms of a structure, built on demand: the energy form (a total potential
with named equality and inequality constraints, for minimization: contact will add its
inequalities) and the mass form (the mass matrix of the unknowns, for time simulation).

Energy form: unknowns x are the free body coordinates (nondimensional, as in z), then the
own variables of elements that have them (a link by elements: its rotations and strains);
    V(x, p) = sum of the elements' strain energies - work of the dead loads,
    g(x, p) = 0 the elements' equalities (their multipliers are the elements' unknowns in
    the residual form, after their own variables), h(x, p) >= 0 their inequalities.
Its stationarity, grad V + J_g^T lam = 0 and g = 0, is the residual form R(z) = 0, with z
the entries of x and lam in the residual form's order (EnergyForm.to_state). Elements whose model is not the gradient of an energy (the constant-stiffness
curved beams, the shooting links) have no energy form and say why.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from flexmech.models.elements import FAMILIES
from flexmech.models.elements.base import NoEnergyForm, NoMassForm
from flexmech.models.errors import MechanismError
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.loads import kinetic_energy, load_potential
from flexmech.models.graph.structure import Structure


@dataclass(frozen=True)
class EnergyForm:
    unknowns: tuple[str, ...]  # x: the free body coordinates, then the elements' own variables
    potential: ca.Function  # (x, p) -> V
    equalities: ca.Function  # (x, p) -> g
    equality_names: tuple[str, ...]  # "<element>.<name>"
    inequalities: ca.Function  # (x, p) -> h
    inequality_names: tuple[str, ...]
    n_multipliers: int  # the equalities' multipliers (residual-form unknowns beyond x)
    x_in_state: tuple[int, ...]  # where each entry of x sits in the residual form's z
    multipliers_in_state: tuple[int, ...]  # where each equality's multiplier sits in z

    def to_state(self, x: np.ndarray, multipliers: np.ndarray) -> np.ndarray:
        """The residual form's z of a point of the energy form and its equalities' multipliers."""
        z = np.zeros(len(self.x_in_state) + len(self.multipliers_in_state))
        z[list(self.x_in_state)] = x
        z[list(self.multipliers_in_state)] = multipliers
        return z

    def x_of_state(self, z: np.ndarray) -> np.ndarray:
        return np.asarray(z, dtype=float)[list(self.x_in_state)]


@dataclass
class SymbolicEnergy:
    """The energy form's expressions, before they become Functions (contact adds to them)."""

    ctx: AssemblyContext
    x: ca.SX
    d: list[ca.SX]  # every body's displacement, in x and p
    names: list[str]
    potential: ca.SX
    equalities: list[tuple[str, ca.SX]]
    inequalities: list[tuple[str, ca.SX]]
    surfaces: dict[str, object]  # element name -> its ElementSurfaces (elements that have them)
    x_in_state: list[int]
    multipliers_in_state: list[int]
    nudge: ca.SX | None = None  # (3 x bodies) added to every body's displacement, when asked for: zero it
    inertia: list = field(default_factory=list)  # every element's InertiaPoints
    inertia_owners: list[str] = field(default_factory=list)  # the element each InertiaPoint belongs to


def symbolic_energy(structure: Structure, nudged: bool = False) -> SymbolicEnergy:
    """The energy form's expressions. nudged: every body's displacement d_b gets a symbol
    added (`nudge`, to be set to zero), so that d/d nudge_b of any term is its generalized
    force on body b, prescribed coordinates included (the reactions of contact forces)."""
    ctx = AssemblyContext(structure)
    x_body = ca.SX.sym("x", len(structure.free))
    d = ctx.displacements(x_body)
    nudge = ca.SX.sym("nudge", 3, len(d)) if nudged else None
    if nudged:
        d = [d_b + nudge[:, b] for b, d_b in enumerate(d)]
    V = load_potential(ctx, d)
    equalities, inequalities, variables, surfaces, inertia, owners = [], [], [x_body], {}, [], []
    names = [structure.coordinate_name(b, c) for b, c in structure.free]
    x_in_state, multipliers_in_state = list(range(len(names))), []
    for t, offset in zip(structure.elements, structure.element_offsets):
        family = FAMILIES.of(t)
        try:
            terms = family.energy_terms(ctx, t, d)
        except NoEnergyForm as reason:
            raise MechanismError(
                f"/elements/{t.name}", f"element '{t.name}' ({family.type}) has no energy form: {reason}"
            ) from None
        n_own = 0 if terms.variables is None else terms.variables.numel()
        if n_own + len(terms.equalities) != t.unknowns:
            raise RuntimeError(
                f"family {family.type}: {t.unknowns} unknowns but {n_own} variables and "
                f"{len(terms.equalities)} equalities"
            )
        if n_own:
            variables.append(terms.variables)
            own_names = family.unknowns(t)[:n_own]
            names += [f"{t.name}.{name}" for name, _ in own_names]
            x_in_state += list(range(offset, offset + n_own))
        multipliers_in_state += list(range(offset + n_own, offset + t.unknowns))
        if terms.surfaces is not None:
            surfaces[t.name] = terms.surfaces
        inertia += terms.inertia
        owners += [t.name] * len(terms.inertia)
        V = V + terms.energy
        equalities += [(f"{t.name}.{name}", g) for name, g in terms.equalities]
        inequalities += [(f"{t.name}.{name}", h) for name, h in terms.inequalities]
    return SymbolicEnergy(
        ctx,
        ca.vertcat(*variables),
        d,
        names,
        V,
        equalities,
        inequalities,
        surfaces,
        x_in_state,
        multipliers_in_state,
        nudge,
        inertia,
        owners,
    )


def energy_form(structure: Structure) -> EnergyForm:
    s = symbolic_energy(structure)
    x, p = s.x, s.ctx.p

    def function(name: str, rows: list[tuple[str, ca.SX]]) -> ca.Function:
        value = ca.vertcat(*[row for _, row in rows]) if rows else ca.SX(0, 1)
        return ca.Function(name, [x, p], [value], ["x", "p"], [name[0]])

    form = EnergyForm(
        tuple(s.names),
        ca.Function("potential", [x, p], [s.potential], ["x", "p"], ["V"]),
        function("g_equalities", s.equalities),
        tuple(name for name, _ in s.equalities),
        function("h_inequalities", s.inequalities),
        tuple(name for name, _ in s.inequalities),
        len(s.equalities),
        tuple(s.x_in_state),
        tuple(s.multipliers_in_state),
    )
    for fn in (form.potential, form.equalities, form.inequalities):
        if fn.has_free():
            raise RuntimeError(f"graph {fn.name()} has free symbols {fn.get_free()}")
    return form


def mass_matrix(structure: Structure) -> ca.Function:
    """(z, p) -> M: the Hessian of the kinetic energy in the unknowns' rates. Body masses fill
    the rows of free body coordinates; elements add theirs where they declare it (none of
    today's families carries mass in its unknowns); an element that has mass its unknowns
    cannot carry is refused by name."""
    ctx = AssemblyContext(structure)
    n = structure.n_unknowns
    z, rate = ca.SX.sym("z", n), ca.SX.sym("zdot", n)
    d, v = ctx.displacements(z), _body_rates(structure, rate)
    T = kinetic_energy(ctx, d, v)
    for t in structure.elements:
        family = FAMILIES.of(t)
        try:
            element = family.kinetic_energy(ctx, t, d, v)
        except NoMassForm as reason:
            raise MechanismError(
                f"/elements/{t.name}", f"element '{t.name}' ({family.type}) has no mass form: {reason}"
            ) from None
        if element is not None:
            T = T + element
    M = ca.hessian(T, rate)[0]
    return ca.Function("mass_matrix", [z, ctx.p], [M], ["z", "p"], ["M"])


def _body_rates(structure: Structure, rate: ca.SX) -> list[ca.SX]:
    """[vx, vy, omega] per body: the free coordinates' rates, zero where prescribed."""
    free_index = {bc: k for k, bc in enumerate(structure.free)}
    return [
        ca.vertcat(*[rate[free_index[(b, c)]] if (b, c) in free_index else ca.SX(0) for c in range(3)])
        for b in range(len(structure.bodies))
    ]


def energy_form_problem(structure: Structure) -> str | None:
    """Why the structure has no energy form (the first element without one, as the form's
    build would refuse it), or None; read from the families without building anything."""
    for t in structure.elements:
        family = FAMILIES.of(t)
        problem = getattr(family, "energy_form_problem", lambda _: None)(t)
        if problem is not None:
            return f"element '{t.name}' ({family.type}) has no energy form: {problem}"
    return None
