"""A harmonic input and the outputs it is watched at, in a modal system's coordinates
(service.vibration.modes): the generalized force per unit of the input (a load's component, a
parameter of the document) and the outputs' rows C = dy/dq, both linearized at the state z.

In the energy form's unknowns the force is -d/dp (dV/dx) and C reads dy/dz at x; an output
that moves with the constraints' forces (a reaction) is refused there: the modes carry the
motion, not the multipliers. In the bodies' coordinates the elements' own unknowns follow the
bodies statically (they are massless), so both are condensed with K_T's blocks."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from models import Mechanism, MechanismError
from models.graph.assembly import graphs_for
from models.graph.structure import Structure
from service.vibration.modes import ModalSystem


@dataclass
class Channel:
    force: np.ndarray  # (n,) nondimensional generalized force per nondimensional unit of the input
    outputs: np.ndarray  # (m, n) C
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
    dy = np.asarray(_derivatives(mech.structure)[0](z, p), dtype=float)[indices]
    if system.coordinates_set == "elements":
        force = np.asarray(mech.graphs.modal_form.parameter_forces(z[list(system.x_in_state)], p))[:, k]
        C = _motion_outputs(dy, system, names)
    else:
        force, C = _condensed(mech, z, p, k, dy, system.n_body)
    if not np.any(force):
        raise MechanismError(
            "/input", f"{pointer} drives no force on the mechanism: name a load's component (/loads/<name>/force/1)"
        )
    kind = mech.parameter_kind(pointer)
    kinds = [mech.graphs.output_kinds[i] for i in indices]
    scale = np.array([mech.nd_per_doc(kind) / mech.nd_per_doc(out) for out in kinds])
    return Channel(force, C, scale, mech.doc_unit(kind), [mech.doc_unit(out) for out in kinds])


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
def _derivatives(structure: Structure) -> tuple[ca.Function, ca.Function]:
    """(z, p) -> dy/dz of every output, and (z, p) -> dR/dp: built once per structure."""
    graphs = graphs_for(structure)
    zs, ps = ca.MX.sym("z", structure.n_unknowns), ca.MX.sym("p", len(structure.parameters))
    return (
        ca.Function("outputs_z", [zs, ps], [ca.jacobian(graphs.outputs(zs, ps), zs)]),
        ca.Function("residual_p", [zs, ps], [ca.jacobian(graphs.residual(zs, ps), ps)]),
    )


def _condensed(mech, z, p, k, dy, n_body):
    """(force, C) on the body coordinates, the elements' unknowns following statically."""
    _, K = mech.graphs.residual_and_tangent(z, p)
    K = np.asarray(K, dtype=float)
    dR = np.asarray(_derivatives(mech.structure)[1](z, p), dtype=float)[:, k]
    b, own = slice(0, n_body), slice(n_body, K.shape[0])
    if K.shape[0] == n_body:
        return -dR, dy
    follow = -np.linalg.solve(K[own, own], np.column_stack([K[own, b], dR[own]]))
    force = -(dR[b] + K[b, own] @ follow[:, -1])
    return force, dy[:, b] + dy[:, own] @ follow[:, :-1]
