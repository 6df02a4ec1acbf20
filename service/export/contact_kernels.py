"""The contact state as an exported task: the frictionless contact problem's KKT conditions
(service.contact.problem's NLP) with complementarity in Fischer-Burmeister form, so that one
semismooth Newton iteration (the C driver's) finds the active set and the forces together:

    phi(h, lam) = h + lam - sqrt(h^2 + lam^2) = 0   <=>   h >= 0, lam >= 0, h lam = 0

per inequality row, h its gap and lam its multiplier (the contact force). Its derivative is
(1 - h/r, 1 - lam/r), r = sqrt(h^2 + lam^2); at r = 0 the element (1 - 1/sqrt 2, 1 - 1/sqrt 2)
of the generalized Jacobian is taken. A separating axis (a polygon site's) whose rows are all
apart (no row carries force) sits where it separates best: nothing else determines it then.

What is not exported: friction (a sticking contact depends on the path it came along, which one
call does not know: MechanismError naming the field), and contact rows whose KKT kernel would
take the export past its build limits (service.costs.build_over_limits, the kernel one more
function of the size model: link surfaces against curved objects have one row per surface point,
each with its second derivatives): the manifest then says why, with the predicted build.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.service.costs import build_over_limits
from flexmech.service.export.direction import direction
from flexmech.service.export.size_model import RowGroup, row_groups, size_of

GAP_FLOOR = 1e-300  # below it r counts as zero
FORCE_FLOOR = 1e-10  # nondimensional: a row carrying less is apart for its axis (rounding leaves ~1e-16)
SHARPNESS = 1e3  # of the soft minimum of gaps (nondimensional: lengths / the largest element)


def _checked_problem(mech: Mechanism):
    from flexmech.service.contact.problem import contact_problem

    for pair in mech.structure.contacts.pairs:  # before the problem is built: seconds for a large one
        if mech.si_values[mech.parameter_index(pair.friction_pointer)] != 0:
            raise MechanismError(
                pair.friction_pointer,
                "the exported contact state is frictionless (a sticking contact depends on the path it came "
                f"along, which one call does not know): set it to 0 to export it, e.g. --set {pair.friction_pointer}=0",
            )
    return contact_problem(mech.structure)


def _kkt(mech: Mechanism, problem):
    """(v, p, F, J) of the frictionless KKT system, v = [w; lam_eq; lam_in], complementarity
    still as the gaps h (rows n_w + n_eq ...)."""
    nlp, n_p = problem.nlp, len(mech.parameters)
    shift = nlp["p"][n_p:]  # the approach's relaxation of the rows: none here
    f = ca.substitute(nlp["f"], shift, ca.DM.zeros(shift.shape))
    g = ca.substitute(nlp["g"], shift, ca.DM.zeros(shift.shape))
    w, p = nlp["x"], nlp["p"][:n_p]
    lam_eq, lam_in = ca.SX.sym("lam_eq", problem.n_eq), ca.SX.sym("lam_in", problem.n_in)
    lagrangian = f + ca.dot(lam_eq, g[: problem.n_eq]) - ca.dot(lam_in, g[problem.n_eq :])
    v = ca.vertcat(w, lam_eq, lam_in)
    F = ca.vertcat(ca.gradient(lagrangian, w), g)
    return v, p, F, ca.jacobian(F, v)


def _fischer_burmeister(problem, v, F, J):
    first = problem.n_w + problem.n_eq
    rows = range(first, first + problem.n_in)
    gaps, lam = F[first:], v[first:]
    r = ca.sqrt(gaps**2 + lam**2)
    corner = 1 - 1 / np.sqrt(2)
    a = ca.if_else(r > GAP_FLOOR, 1 - gaps / r, corner)
    b = ca.if_else(r > GAP_FLOOR, 1 - lam / r, corner)
    J_fb = ca.diag(a) @ J[first:, :] + ca.diag(b) @ ca.SX(ca.DM.eye(v.numel())[list(rows), :])
    F = ca.vertcat(F[:first], gaps + lam - r)
    J = ca.vertcat(J[:first, :], J_fb)
    carries = [lam[k] > FORCE_FLOOR for k in range(problem.n_in)]
    for j in range(problem.n_axes // 2):
        mine = [problem.n_element_in + k for k, axis in enumerate(problem.row_axes) if axis == j]
        held = 1
        for k in mine:
            held = held * ca.if_else(carries[k], 0, 1)
        rules = _best_line(problem, v, gaps, mine, problem.n_x + 2 * j)
        for row, rule in zip((problem.n_x + 2 * j, problem.n_x + 2 * j + 1), rules):
            F[row] = (1 - held) * F[row] + held * rule[0]
            J[row, :] = (1 - held) * J[row, :] + held * rule[1]
    return F, J


def _soft_minimum(values: list) -> ca.SX:
    """A smooth minimum (log-sum-exp about the least value, sharpness SHARPNESS)."""
    least = values[0]
    for value in values[1:]:
        least = ca.fmin(least, value)
    total = sum(ca.exp(-SHARPNESS * (value - least)) for value in values)
    return least - ca.log(total) / SHARPNESS


def _best_line(problem, v, gaps, rows: list[int], first: int):
    """While no row of a separating axis carries force, nothing determines the axis: its angle
    stays (a zero step) and its offset splits the clearance evenly between the site's least gap
    and the object's (as service.contact.solve.separated puts it)."""
    site = _soft_minimum([gaps[k] for k in rows if problem.row_pushes[k - problem.n_element_in]])
    other = _soft_minimum([gaps[k] for k in rows if not problem.row_pushes[k - problem.n_element_in]])
    unit = ca.SX(ca.DM.eye(v.numel())[first, :])
    return (ca.SX(0), unit), (site - other, ca.jacobian(site - other, v))


def contact_kernel(mech: Mechanism, base: str = "x"):
    """(the contact problem, v, p, its KKT system (v, p) -> (F, J), and that system as the size
    model counts it: one more generated function, of its instructions and v's size); None
    without contacts. Seconds for many rows: its second derivatives are built."""
    if mech.structure.contacts is None or not mech.structure.contacts.pairs:
        return None
    problem = _checked_problem(mech)
    v, p, F, J = _kkt(mech, problem)
    F, J = _fischer_burmeister(problem, v, F, J)
    system = ca.Function(f"{base}_contact_system", [v, p], [F, J], ["v", "p"], ["F", "J"])
    kernel = RowGroup(f"the contact KKT kernel ({problem.n_in} rows)", system.n_instructions(), v.numel())
    return problem, v, p, system, kernel


def contact_functions(mech: Mechanism, names: tuple[str, ...], base: str):
    """(step (v, p) -> (dv, norm), outputs (v, p) -> y in document units named `names` (as
    service.export.plan.contact_outputs chose them), units, n_v, start (p) -> v0: undeformed and
    apart, each separating axis at its guess) of the contact state; None without contacts; a str
    (why) when it is too large."""
    built = contact_kernel(mech, base)
    if built is None:
        return None
    problem, v, p, system, kernel = built
    over = build_over_limits(size_of((*row_groups(mech.structure), kernel)))
    if over is not None:
        return f"its KKT kernel ({problem.n_in} contact rows with their second derivatives) would be too large: {over}"
    vm, pm = ca.MX.sym("v", v.numel()), ca.MX.sym("p", p.numel())
    Fm, Jm = system(vm, pm)
    step = ca.Function(f"{base}_contact_step", [vm, pm], [*direction(Fm, Jm)], ["v", "p"], ["dv", "norm"])
    chosen = tuple(names)
    missing = [n for n in chosen if n not in problem.output_names]
    if missing:
        raise MechanismError(
            "/contact_outputs", f"unknown contact output '{missing[0]}' (e.g. {', '.join(problem.output_names[:7])})"
        )
    indices = [problem.output_names.index(n) for n in chosen]
    kinds = [problem.output_kinds[i] for i in indices]
    zeros_in, zeros_pairs = ca.DM.zeros(problem.n_in), ca.DM.zeros(problem.n_pairs)
    y = problem.outputs(ca.vertcat(vm, zeros_pairs), pm, zeros_in, zeros_pairs, ca.DM.zeros(problem.n_rows))
    scaled = ca.vertcat(*[y[i] / mech.nd_per_doc(k) for i, k in zip(indices, kinds)])
    outputs = ca.Function(f"{base}_contact_outputs", [vm, pm], [ca.densify(scaled)], ["v", "p"], ["y"])
    x = ca.MX.zeros(problem.n_x)
    start = ca.vertcat(x, problem.axes_guess(x, pm), ca.MX.zeros(problem.n_eq + problem.n_in))
    first = ca.Function(f"{base}_contact_start", [pm], [ca.densify(start)], ["p"], ["v0"])
    return step, outputs, chosen, tuple(mech.doc_unit(k) for k in kinds), v.numel(), first
