"""The CasADi Functions an export generates to C, one per task, and a Python twin of the C
iteration over them (its worst-case iteration count goes into the manifest).

Each step Function returns the Newton direction and |R|_inf at its point: the C driver does
the bounded, damped iteration around it, so that the iteration count, the line search and
the status stay visible and fixed at export. Linear solves are CasADi's sparse QR, which
code-generates without allocation (the work vector's size is fixed at export).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.service.deadline import stop_requested
from flexmech.service.export.direction import direction
from flexmech.service.export.plan import ExportPlan
from flexmech.service.units import matrix_to_doc


@dataclass(frozen=True)
class ContactTask:
    """The contact state's Functions (service.export.contact_kernels): step (v, p) -> (dv,
    norm), outputs (v, p) -> y in document units, named `names` in `units`; n_v unknowns."""

    step: ca.Function
    outputs: ca.Function
    names: tuple[str, ...]
    units: tuple[str, ...]
    n_v: int
    start: ca.Function  # (p) -> the cold start


@dataclass(frozen=True)
class ExportFunctions:
    """Functions of one plan, each named <plan name>_kernel_<task>:
    eq_step (z, p) -> (dz, norm); outputs (z, p) -> y (document units);
    stiffness (z, p) -> K (body coordinates, document units, row-major when read flat in C);
    target_step (x = [z; input], p, goal) -> (dx, norm), or None without a target."""

    eq_step: ca.Function
    outputs: ca.Function
    stiffness: ca.Function
    target_step: ca.Function | None
    contact: ContactTask | None = None
    contact_note: str = ""  # why a contact document's export has no contact task

    def all(self) -> list[ca.Function]:
        contact = (self.contact.step, self.contact.outputs, self.contact.start) if self.contact else ()
        return [f for f in (self.eq_step, self.outputs, self.stiffness, self.target_step, *contact) if f is not None]


def _stiffness(mech: Mechanism, z: ca.MX, p: ca.MX, K: ca.MX, name: str) -> ca.Function:
    """The body coordinates' stiffness with the elements' own unknowns condensed out, as
    service.solvers.stiffness.condensed: the inverse of the leading block of K^-1."""
    n, nb = mech.n_free, mech.n_body_coordinates
    if n > nb:
        pick = ca.DM.eye(n)[:, :nb]
        compliance = ca.solve(K, pick, "qr")[:nb, :]
        K = ca.solve(compliance, ca.DM.eye(nb), "qr")
    factors = matrix_to_doc(mech, np.ones((nb, nb)))
    return ca.Function(name, [z, p], [ca.densify(K * ca.DM(factors)).T], ["z", "p"], ["K_row_major"])


def _outputs(mech: Mechanism, plan: ExportPlan, name: str) -> ca.Function:
    z, p = ca.SX.sym("z", mech.n_free), ca.SX.sym("p", len(mech.parameters))
    y = mech.graphs.outputs(z, p)
    chosen = ca.vertcat(*[y[o.index] * o.unit_per_nd for o in plan.outputs])
    return ca.Function(name, [z, p], [ca.densify(chosen)], ["z", "p"], ["y"])


def _target_step(
    mech: Mechanism, plan: ExportPlan, name: str, R: ca.MX, K: ca.MX, z: ca.MX, p: ca.MX
) -> ca.Function | None:
    """The Newton step of the equilibrium augmented with "output = goal", unknowns x = [z; input].
    Its Jacobian reuses the equilibrium's K (the same generated kernel, called at the input's
    value) and borders it with one more column (dR/d input) and one more row (the output's
    gradient), differentiated in SX in the input's one direction (for a load, a few nodes):
    about half the code of differentiating the augmented system whole."""
    if plan.target is None:
        return None
    n, np_ = mech.n_free, len(mech.parameters)
    slot = plan.inputs[plan.target.input].slot
    reached = plan.target.output
    pick = ca.DM.zeros(np_)
    pick[slot] = 1
    zs, ps, lam = ca.SX.sym("z", n), ca.SX.sym("p", np_), ca.SX.sym("input")
    ps_at = ps + (lam - ps[slot]) * pick
    y = mech.graphs.outputs(zs, ps_at)[reached.index] * reached.unit_per_nd
    border = ca.Function(
        f"{name}_border",
        [zs, ps, lam],
        [y, ca.jacobian(mech.graphs.residual(zs, ps_at), lam), ca.jacobian(y, zs), ca.jacobian(y, lam)],
    )
    x, goal = ca.MX.sym("x", n + 1), ca.MX.sym("goal")
    p_at = p + (x[n] - p[slot]) * pick
    R_at, K_at = ca.substitute([R, K], [z, p], [x[:n], p_at])
    value, column, row, corner = border(x[:n], p, x[n])
    G = ca.vertcat(R_at, value - goal)
    J = ca.blockcat([[K_at, column], [row, corner]])
    dx, norm = direction(G, J)
    return ca.Function(name, [x, p, goal], [dx, norm], ["x", "p", "goal"], ["dx", "norm"])


def _residual_and_tangent(mech: Mechanism, z: ca.MX, p: ca.MX) -> tuple[ca.MX, ca.MX]:
    """R and K from their row groups (models.graph.assembly.residual_by_rows): the same numbers
    as graphs.residual_and_tangent, in generated functions a compiler optimizes in seconds."""
    from flexmech.models.graph.assembly import residual_by_rows

    # the structure without names: its expressions are the ones the graphs were built from
    pieces = [f(z, p) for _, f in residual_by_rows(mech.structure.unnamed)]
    return ca.vertcat(*[r for r, _ in pieces]), ca.vertcat(*[k for _, k in pieces])


def export_functions(mech: Mechanism, plan: ExportPlan) -> ExportFunctions:
    if mech.n_free == 0:
        raise MechanismError(
            "/bodies", "nothing moves: every body is fixed or prescribed, there is no equilibrium to export"
        )
    z, p = ca.MX.sym("z", mech.n_free), ca.MX.sym("p", len(mech.parameters))
    R, K = _residual_and_tangent(mech, z, p)
    dz, norm = direction(R, K)
    base = f"{plan.name}_kernel"  # the tasks' own names (<name>_stiffness, ...) belong to the driver
    functions = ExportFunctions(
        eq_step=ca.Function(f"{base}_eq_step", [z, p], [dz, norm], ["z", "p"], ["dz", "norm"]),
        outputs=_outputs(mech, plan, f"{base}_outputs"),
        stiffness=_stiffness(mech, z, p, K, f"{base}_stiffness"),
        target_step=_target_step(mech, plan, f"{base}_target_step", R, K, z, p),
        **_contact(mech, plan, base),
    )
    for f in functions.all():
        if f.has_free():
            raise RuntimeError(f"export Function {f.name()} has free symbols {f.get_free()}")
    return functions


def _contact(mech: Mechanism, plan: ExportPlan, base: str) -> dict:
    """The contact task's fields of ExportFunctions, as plan.options.contact asks: "auto" exports
    it when the document has contacts and its kernel is within bounds (else notes why), "yes"
    insists (MechanismError), "no" leaves it out."""
    from flexmech.service.export.contact_kernels import contact_functions

    choice = plan.options.contact
    if choice == "no":
        return {}
    try:
        found = contact_functions(mech, tuple(c.name for c in plan.contact_outputs), base)
    except MechanismError as exc:
        if choice == "yes" or exc.pointer == "/contact_outputs":
            raise
        return {"contact_note": f"no contact task: {exc.pointer}: {exc.problem}"}
    if found is None:
        if choice == "yes":
            raise MechanismError("/contact", "the document has no contacts (contacts.pairs)")
        return {}
    if isinstance(found, str):
        if choice == "yes":
            raise MechanismError("/contact", f"the contact state cannot be exported: {found}")
        return {"contact_note": f"no contact task: {found}"}
    return {"contact": ContactTask(*found)}


@dataclass
class Iteration:
    status: int  # the C status codes: 0 converged, 1 not converged, 4 not finite
    x: np.ndarray
    iterations: int


def iterate(step, x0: np.ndarray, args: tuple, plan: ExportPlan) -> Iteration:
    """The C driver's damped Newton (sources/driver.c.in, newton()), step for step: a step is
    accepted when it lowers |R|_inf, or after line_search_halvings halvings."""
    options = plan.options
    x = np.array(x0, dtype=float)
    try:
        dx, norm = _evaluate(step, x, args)
    except RuntimeError:  # the C kernel returns non-finite numbers: NOT_FINITE
        return Iteration(4, x, 0)
    for k in range(options.max_iterations + 1):
        if not np.isfinite(norm[0]):
            return Iteration(4, x, k)
        if norm[0] <= options.tolerance:
            return Iteration(0, x, k)
        if k == options.max_iterations or stop_requested():  # a job's export stops when cancelled or out of time
            break
        t = 1.0
        for halving in range(options.line_search_halvings + 1):
            trial = x - t * dx
            try:
                dx_t, norm_t = _evaluate(step, trial, args)
            except RuntimeError:
                return Iteration(4, x, k)
            if (np.isfinite(norm_t[0]) and norm_t[0] < norm[0]) or halving == options.line_search_halvings:
                break
            t *= 0.5
        x, dx, norm = trial, dx_t, norm_t
    return Iteration(1, x, options.max_iterations)


def _evaluate(step, x: np.ndarray, args: tuple) -> tuple[np.ndarray, np.ndarray]:
    dx, norm = step(x, *args)
    return np.asarray(dx, dtype=float).ravel(), np.asarray(norm, dtype=float).ravel()
