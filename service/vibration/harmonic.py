"""A harmonic input and the outputs it is watched at, in a modal system's coordinates
(service.vibration.modes), linearized at the state z.

A load's component: the generalized force per unit of it (in the energy form's unknowns
-d/dp (dV/dx); in the bodies' coordinates -dR/dp with the elements' unknowns following
statically, they are massless). A prescribed displacement (a shaken body): its quasi-static
motion x_qs (the state's static sensitivity, every constraint it moves kept) plus the remainder
it drives, omega^2 (M x_qs + M_xp), M_xp the inertia of the masses it carries (models.graph.modal).
The outputs' rows C = dy/dq, with their direct dependence on the input; in the energy form's
unknowns an output that moves with the constraints' forces (a reaction) is refused: the modes
carry the motion, not the multipliers."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.graph.assembly import graphs_for
from flexmech.models.graph.modal import motion_coupling
from flexmech.models.graph.structure import Structure
from flexmech.service.vibration.modes import ModalSystem


@dataclass
class Channel:
    force: np.ndarray  # (n,) nondimensional generalized force per nondimensional unit of the input
    outputs: np.ndarray  # (m, n) C
    inertial: np.ndarray  # (n,) a prescribed motion's inertial push per unit, times omega^2 (zero for a load)
    direct: np.ndarray  # (m,) the outputs' response that is not modal (a prescribed motion's quasi-static one)
    carried: np.ndarray  # (n,) M x_qs: the momentum a prescribed motion carries (air drag alpha M acts on it)
    scale: np.ndarray  # (m,) document (output unit / input unit) per nondimensional
    input_unit: str
    output_units: list[str]


def channel(mech: Mechanism, z: np.ndarray, system: ModalSystem, pointer: str, names: list[str]) -> Channel:
    p = mech.p()
    try:
        k = mech.parameter_index(pointer)
    except MechanismError as exc:
        raise MechanismError("/input", f"{pointer}: {exc.problem}") from None
    indices = _output_indices(mech, names)
    outputs_z, outputs_p, residual_p = output_derivatives(mech.structure)
    dy = np.asarray(outputs_z(z, p), dtype=float)[indices]
    direct = np.asarray(outputs_p(z, p), dtype=float)[indices, k]
    if system.coordinates_set == "elements":
        x = z[list(system.x_in_state)]
        force = np.asarray(mech.graphs.modal_form.parameter_forces(x, p))[:, k]
        C = _motion_outputs(dy, system, names)
    else:
        force, C = _condensed(mech, z, p, k, dy, system.n_body)
    n = len(system.coordinates)
    if not moves_a_body(mech, pointer):
        if not np.any(force):
            raise MechanismError(
                "/input",
                f"{pointer} drives no force on the mechanism: name a load's component (/loads/<name>/force/1) "
                "or a prescribed displacement's (/loads/<name>/dx)",
            )
        zero = np.zeros(n)
        link = (force, C, zero, direct, zero)
    else:
        link = _prescribed_motion(mech, z, p, k, system, C, direct, np.asarray(residual_p(z, p), dtype=float)[:, k])
    kind = mech.parameter_kind(pointer)
    kinds = [mech.graphs.output_kinds[i] for i in indices]
    scale = np.array([mech.nd_per_doc(kind) / mech.nd_per_doc(out) for out in kinds])
    return Channel(*link, scale, mech.doc_unit(kind), [mech.doc_unit(out) for out in kinds])


def _prescribed_motion(mech, z, p, k, system: ModalSystem, C, direct, dR):
    """A prescribed displacement P e^(i omega t) as a quasi-static motion x_qs P (every constraint
    it moves kept) plus the dynamic remainder it drives: omega^2 (M x_qs + M_xp) P. Damping
    ratios and Rayleigh's beta act on the remainder (the deformation), Rayleigh's alpha also on
    the carried motion (it drags absolute velocities)."""
    K = np.asarray(mech.graphs.residual_and_tangent(z, p)[1], dtype=float)
    dz = -np.linalg.solve(K, dR)
    if system.coordinates_set == "elements":
        quasi_static = dz[system.x_in_state]
        coupling = np.asarray(motion_coupling(mech.structure)(z[system.x_in_state], p))[:, k]
    else:
        quasi_static, coupling = dz[: system.n_body], np.zeros(system.n_body)
    carried = system.M @ quasi_static
    return np.zeros(len(quasi_static)), C, carried + coupling, direct + C @ quasi_static, carried


def moves_a_body(mech: Mechanism, pointer: str) -> bool:
    """Whether the field is a prescribed displacement of a body (it moves masses with it)."""
    return any(pointer in row for row in mech.structure.prescribed)


def _output_indices(mech: Mechanism, names: list[str]) -> list[int]:
    known = mech.graphs.output_names
    for i, name in enumerate(names):
        if name not in known:
            bodies = [n for n in known if n.startswith("bodies.")][:9]
            raise MechanismError(f"/outputs/{i}", f"no output '{name}' (outputs such as {', '.join(bodies)})")
    return [known.index(name) for name in names]


def _motion_outputs(dy: np.ndarray, system: ModalSystem, names: list[str]) -> np.ndarray:
    multipliers = dy[:, list(system.multipliers_in_state)]
    for i, row in enumerate(multipliers):
        if np.any(np.abs(row) > 1e-12 * max(np.abs(dy[i]).max(), 1e-300)):
            raise MechanismError(
                f"/outputs/{i}",
                f"'{names[i]}' moves with the constraints' forces, which the modes do not carry: "
                "watch positions, rotations, strains or stresses",
            )
    return dy[:, list(system.x_in_state)]


@lru_cache(maxsize=16)
def output_derivatives(structure: Structure) -> tuple[ca.Function, ca.Function, ca.Function]:
    """(z, p) -> dy/dz and dy/dp of every output, and (z, p) -> dR/dp: built once per structure."""
    graphs = graphs_for(structure)
    zs, ps = ca.MX.sym("z", structure.n_unknowns), ca.MX.sym("p", len(structure.parameters))
    y = graphs.outputs(zs, ps)
    return (
        ca.Function("outputs_z", [zs, ps], [ca.jacobian(y, zs)]),
        ca.Function("outputs_p", [zs, ps], [ca.jacobian(y, ps)]),
        ca.Function("residual_p", [zs, ps], [ca.jacobian(graphs.residual(zs, ps), ps)]),
    )


def _condensed(mech, z, p, k, dy, n_body):
    """(force, C) on the body coordinates, the elements' unknowns following statically."""
    _, K = mech.graphs.residual_and_tangent(z, p)
    K = np.asarray(K, dtype=float)
    dR = np.asarray(output_derivatives(mech.structure)[2](z, p), dtype=float)[:, k]
    b, own = slice(0, n_body), slice(n_body, K.shape[0])
    if K.shape[0] == n_body:
        return -dR, dy
    follow = -np.linalg.solve(K[own, own], np.column_stack([K[own, b], dR[own]]))
    force = -(dR[b] + K[b, own] @ follow[:, -1])
    return force, dy[:, b] + dy[:, own] @ follow[:, :-1]
