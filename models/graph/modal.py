"""The modal form: what small vibration about an equilibrium needs, from the energy form's
expressions (models.graph.forms) in its unknowns x (nondimensional; time in seconds):

    K(x, lam, p) = d2/dx2 (V + lam . g)   the stiffness, prestress and load stiffness included
    G(x, p) = dg/dx                         the constraints: the modes live in their null space
    M_o(x, p)                               the mass matrix of each owner of mass (a body with
                                            mass, an element with density); M = sum of them
    F(x, p) = [M r_x, M r_y]                the generalized forces of a unit uniform acceleration
                                            along x and along y, fixed bodies included (so a
                                            link clamped to the ground shakes with it): with a
                                            mode shape they give its participation factor
    J(x, p)                                 where the elements' mass points move, per unit x
    B(x, p) = -d/dp (dV/dx)                 the generalized force per unit of each parameter
                                            (a load's component: its harmonic force's shape)

A mass point of an element is one of its InertiaPoints (the quadrature points of its
discretization, so M is the element's consistent mass)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca

from flexmech.models.graph.forms import symbolic_energy
from flexmech.models.graph.loads import body_kinetic_energies, mass_centres
from flexmech.models.graph.structure import Structure


@dataclass(frozen=True)
class ModalForm:
    unknowns: tuple[str, ...]
    n_equalities: int
    x_in_state: tuple[int, ...]  # where x and the multipliers sit in the residual form's z
    multipliers_in_state: tuple[int, ...]
    owners: tuple[str, ...]  # "bodies/<name>" or "elements/<name>", one per mass matrix
    point_owners: tuple[str, ...]  # the element of each mass point
    # (x, lam, p) -> (K, G, the owners' M_o stacked (owners n x n), F (n x 2), the mass points'
    # positions (2 x k), J (2k x n): rows x0, y0, x1, y1, ...): one call for a modes run
    state: ca.Function
    masses: ca.Function  # (x, p) -> M = sum of the M_o
    total_mass: ca.Function  # (p) -> the mechanism's mass (its bodies' and elements')
    parameter_forces: ca.Function  # (x, p) -> B (n x parameters)


def modal_form(structure: Structure) -> ModalForm:
    s = symbolic_energy(structure)
    x, p = s.x, s.ctx.p
    n = x.numel()
    g = ca.vertcat(*[row for _, row in s.equalities]) if s.equalities else ca.SX(0, 1)
    lam = ca.SX.sym("lam", g.numel())
    K = ca.hessian(s.potential + ca.dot(lam, g), x)[0]
    rate = ca.SX.sym("xdot", n)

    def speed(expr: ca.SX) -> ca.SX:
        return ca.jtimes(expr, x, rate)

    energies: dict[str, ca.SX] = {}
    for b, T in body_kinetic_energies(s.ctx, s.d, [speed(d_b) for d_b in s.d]):
        energies[f"bodies/{structure.bodies[b]}"] = T
    for point, owner in zip(s.inertia, s.inertia_owners):
        T = 0.5 * point.mass * ca.sumsqr(speed(point.position))
        if point.angle is not None and point.rotary is not None:
            T = T + 0.5 * point.rotary * speed(point.angle) ** 2
        key = f"elements/{owner}"
        energies[key] = energies.get(key, ca.SX(0)) + T
    owners = tuple(energies)
    masses = [ca.hessian(T, rate)[0] for T in energies.values()]
    stacked_masses = ca.vertcat(*masses) if masses else ca.SX(0, n)
    total_matrix = sum(masses[1:], masses[0]) if masses else ca.SX.zeros(n, n)
    centres = mass_centres(s.ctx, s.d)
    moment = [
        sum((m * c[axis] for _, m, c in centres), ca.SX(0))
        + sum((q.mass * q.position[axis] for q in s.inertia), ca.SX(0))
        for axis in (0, 1)
    ]
    total = sum((m for _, m, _ in centres), ca.SX(0)) + sum((q.mass for q in s.inertia), ca.SX(0))
    uniform = ca.horzcat(*[ca.gradient(moment[axis], x) for axis in (0, 1)])
    where = ca.horzcat(*[q.position for q in s.inertia]) if s.inertia else ca.SX(2, 0)
    stacked = ca.vec(where)
    return ModalForm(
        tuple(s.names),
        g.numel(),
        tuple(s.x_in_state),
        tuple(s.multipliers_in_state),
        owners,
        tuple(s.inertia_owners),
        ca.Function(
            "modal_state",
            [x, lam, p],
            [ca.densify(e) for e in (K, ca.jacobian(g, x), stacked_masses, uniform, where, ca.jacobian(stacked, x))],
            ["x", "lam", "p"],
            ["K", "G", "M_owners", "F", "positions", "J"],
        ),
        ca.Function("masses", [x, p], [total_matrix], ["x", "p"], ["M"]),
        ca.Function("total_mass", [p], [total], ["p"], ["mass"]),
        ca.Function("parameter_forces", [x, p], [-ca.jacobian(ca.gradient(s.potential, x), p)], ["x", "p"], ["B"]),
    )


@lru_cache(maxsize=16)
def state_mass(structure: Structure) -> ca.Function:
    """(z, p) -> M_z: the mass matrix over the residual form's unknowns z (the energy form's
    masses placed at their unknowns, the multipliers massless; without an energy form, the
    bodies' masses of models.graph.forms.mass_matrix)."""
    from flexmech.models.errors import MechanismError
    from flexmech.models.graph.forms import mass_matrix

    try:
        form = modal_form(structure)
    except MechanismError:
        return mass_matrix(structure)
    n = structure.n_unknowns
    z, p = ca.SX.sym("z", n), ca.SX.sym("p", len(structure.parameters))
    x = z[list(form.x_in_state)]
    M = ca.SX.zeros(n, n)
    if form.owners:
        total = form.masses(x, p)
        index = list(form.x_in_state)
        place = ca.DM(ca.Sparsity.triplet(n, len(index), index, list(range(len(index)))), 1.0)
        M = ca.mtimes([place, total, place.T])
    return ca.Function("state_mass", [z, p], [M], ["z", "p"], ["M"])


@lru_cache(maxsize=16)
def motion_coupling(structure: Structure) -> ca.Function:
    """(x, p) -> M_xp = d2T / dxdot dpdot: the inertia a moving parameter (a prescribed
    displacement) puts on the unknowns, through the masses whose positions it moves (the
    points of a link that starts on a shaken body). Its harmonic motion P e^(i omega t) pushes
    the unknowns by omega^2 M_xp P besides its stiffness coupling."""
    s = symbolic_energy(structure)
    x, p = s.x, s.ctx.p
    xdot, pdot = ca.SX.sym("xdot", x.numel()), ca.SX.sym("pdot", p.numel())

    def speed(expr: ca.SX) -> ca.SX:
        return ca.jtimes(expr, x, xdot) + ca.jtimes(expr, p, pdot)

    T = sum((T_b for _, T_b in body_kinetic_energies(s.ctx, s.d, [speed(d_b) for d_b in s.d])), ca.SX(0))
    for point in s.inertia:
        T = T + 0.5 * point.mass * ca.sumsqr(speed(point.position))
        if point.angle is not None and point.rotary is not None:
            T = T + 0.5 * point.rotary * speed(point.angle) ** 2
    coupling = ca.jacobian(ca.gradient(T, xdot), pdot)
    return ca.Function("motion_coupling", [x, p], [coupling], ["x", "p"], ["M_xp"])
