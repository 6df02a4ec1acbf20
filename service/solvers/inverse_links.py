"""Forward samples and the inverse analysis of link networks (Lan 2005, Sec. 5.3).

`link_states` samples a solved link anywhere along u (the forward model's dense output).
`inverse_links` takes the deformed angle psi(u) of every link and some internal forces and
returns the initial shapes eta(u) and the unknown external loads (models.beams.link_inverse).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import lru_cache

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.beams.link_inverse import InverseLayout, PsiLayout, inverse_graphs_for
from flexmech.models.documents.document import PrescribedDisplacement
from flexmech.models.elements import FAMILIES
from flexmech.models.elements.link import attach, link_shooting
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.structure import Structure
from flexmech.service.solvers.newton import NewtonOptions, Status, iterate_dense


# --- forward dense output -------------------------------------------------------------------
@lru_cache(maxsize=32)
def invertible(structure: Structure) -> list:
    """The elements whose shape the inverse solves (their family says: links by shooting)."""
    return [t for t in structure.elements if getattr(FAMILIES.of(t), "invertible", False)]


def _sampler(structure: Structure, name: str, at: tuple[float, ...]) -> ca.Function:
    ctx = AssemblyContext(structure)
    index = [t.name for t in structure.elements].index(name)
    link, offset = structure.elements[index], structure.element_offsets[index]
    z = ca.SX.sym("z", structure.n_unknowns)
    shooting = link_shooting(ctx, link)
    solution = attach(ctx, link, shooting, ctx.displacements(z), z[offset : offset + link.unknowns]).solution
    states = []
    for u in at:
        k = min(int(u * link.intervals), link.intervals - 1)
        start = k / link.intervals
        state = solution.nodes[k]
        if u > start:
            state = shooting.step(k, state, solution.n, H=u - start, u0=start)
        states.append(state[:4])
    return ca.Function("link_states", [z, ctx.p], [ca.horzcat(*states)], ["z", "p"], ["states"])


def link_states(mech: Mechanism, z: np.ndarray, name: str, u) -> dict[str, np.ndarray]:
    """psi [rad], m, x, y (document units) of link `name` at the positions u in [0, 1], from
    the nodes of the solution z with one high-order step each."""
    names = [link.name for link in invertible(mech.structure)]
    if name not in names:
        raise MechanismError("/elements", f"no link named '{name}' (links: {', '.join(names) or 'none'})")
    at = tuple(float(x) for x in np.atleast_1d(u))
    if any(not 0.0 <= x <= 1.0 for x in at):
        raise MechanismError("/u", "positions along a link must lie in [0, 1]")
    states = np.asarray(_sampler(mech.structure, name, at)(z, mech.p()))
    return {
        "psi": states[0],
        "m": states[1] / mech.nd_per_doc("moment"),
        "x": states[2] / mech.nd_per_doc("length"),
        "y": states[3] / mech.nd_per_doc("length"),
    }


# --- inverse ---------------------------------------------------------------------------------
@dataclass
class LinkInverseResult:
    status: Status
    message: str
    iterations: int
    solver_residual: float  # nondimensional infinity norm of every row
    seconds: float
    loads: dict[str, float]  # the unknown load components, document units
    links: dict[str, dict] = field(default_factory=dict)  # h, v, moments; u, eta, x0, y0 at the nodes
    bodies: dict[str, dict] = field(default_factory=dict)  # undeformed position and rotation

    @property
    def converged(self) -> bool:
        return self.status == "converged"


def _psi_layout(pointer: str, spec) -> tuple[PsiLayout, list[float]]:
    if not isinstance(spec, dict) or set(spec) not in ({"polynomial"}, {"samples", "u"}):
        raise MechanismError(
            pointer, 'give {"polynomial": [c0, c1, ...]} or {"samples": [...], "u": [...]} (angles in radians)'
        )
    if "polynomial" in spec:
        values = _numbers(f"{pointer}/polynomial", spec["polynomial"])
        return PsiLayout("polynomial", len(values)), values
    values = _numbers(f"{pointer}/samples", spec["samples"])
    at = _numbers(f"{pointer}/u", spec["u"])
    if len(at) != len(values):
        raise MechanismError(
            f"{pointer}/u", f"inconsistent inverse data: {len(at)} positions for {len(values)} samples"
        )
    if len(values) < 2:
        raise MechanismError(f"{pointer}/samples", "inconsistent inverse data: at least two samples are needed")
    if any(not 0.0 <= x <= 1.0 for x in at) or len(set(at)) != len(at):
        raise MechanismError(f"{pointer}/u", "inconsistent inverse data: positions must be distinct and lie in [0, 1]")
    return PsiLayout("samples", len(values), tuple(at)), values


def _numbers(pointer: str, values) -> list[float]:
    if (
        not isinstance(values, (list, tuple))
        or not values
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) for v in values)
    ):
        raise MechanismError(pointer, "expected a non-empty list of finite numbers")
    return [float(v) for v in values]


def inverse_links(
    mech: Mechanism,
    shapes: dict,
    internal_forces: dict,
    unknown_loads: list[str],
    options: NewtonOptions = NewtonOptions(),
) -> LinkInverseResult:
    """Initial shapes and unknown loads from deformed shapes and internal forces.

    shapes: {link: {"polynomial": [c0, ...]} or {"samples": [...], "u": [...]}}, psi in rad;
    internal_forces: {link: {"h": value, "v": value}} (either or both, document force unit);
    unknown_loads: pointers of load components whose values are sought, e.g.
    "/loads/F/force/0"; the other loads keep their document values.
    """
    links = _invertible_links(mech)
    layouts, data = _shape_data(links, shapes)
    specified, specified_values = _specified_forces(mech, links, internal_forces)
    unknown_indices = _unknown_loads(mech, unknown_loads)
    if len(specified) != len(unknown_indices):
        raise MechanismError(
            "/internal_forces",
            (
                f"inconsistent inverse data: {len(specified)} internal force component(s) given for "
                f"{len(unknown_indices)} unknown load component(s); they must be equal (Lan 2005 Sec. 5.3.2)"
            ),
        )
    layout = InverseLayout(tuple(layouts), tuple(unknown_indices), tuple(specified))
    graphs = inverse_graphs_for(mech.structure, layout)
    p, q = mech.p(), np.array(data + specified_values)
    started = time.perf_counter()

    def evaluate(z):
        R, K = graphs.residual_and_tangent(z, p, q)
        return np.asarray(R).ravel(), np.asarray(K)

    status, z, norm, iterations, _, message = iterate_dense(evaluate, np.zeros(graphs.n_unknowns), options)
    seconds = time.perf_counter() - started
    y = np.asarray(graphs.results(z, p, q)).ravel()
    values = {n: float(v) / mech.nd_per_doc(k) for n, k, v in zip(graphs.result_names, graphs.result_kinds, y)}
    loads = {}
    for k, index in enumerate(unknown_indices):
        kind = mech.parameters[index].kind
        loads[mech.parameters[index].pointer] = float(z[mech.structure.n_unknowns + k]) / mech.nd_per_doc(kind)
    result = LinkInverseResult(status, message, iterations, norm, seconds, loads)
    _report_links(mech, values, result)
    return result


def _invertible_links(mech: Mechanism) -> list:
    structure = mech.structure
    links = invertible(structure)
    if not links:
        raise MechanismError("/shapes", "this mechanism has no links to invert")
    for name, load in mech.document.loads.items():
        if isinstance(load, PrescribedDisplacement):
            raise MechanismError(
                f"/loads/{name}",
                "the link inverse takes forces and moments; prescribed displacements belong to the forward problem",
            )
    for element in structure.elements:
        if not getattr(FAMILIES.of(element), "invertible", False) and element.unknowns:  # links by shooting
            raise MechanismError(
                f"/elements/{element.name}",
                "the link inverse takes links and elements whose "
                f"forces follow from the body motions; '{element.name}' ({element.family}) "
                "has unknowns of its own",
            )
    for link in links:
        if link.shear or link.axial or link.weighs:
            raise MechanismError(
                f"/elements/{link.name}", "the link inverse takes inextensible, massless links without shear"
            )
    return links


def _shape_data(links: list, shapes) -> tuple[list[PsiLayout], list[float]]:
    names = [link.name for link in links]
    if not isinstance(shapes, dict):
        raise MechanismError("/shapes", "expected an object: link name -> deformed shape")
    for name in shapes:
        if name not in names:
            raise MechanismError(f"/shapes/{name}", f"no link named '{name}' (links: {', '.join(names)})")
    layouts, data = [], []
    for name in names:
        if name not in shapes:
            raise MechanismError(
                f"/shapes/{name}", "inconsistent inverse data: the deformed shape of every link is needed"
            )
        layout, values = _psi_layout(f"/shapes/{name}", shapes[name])
        layouts.append(layout)
        data.extend(values)
    return layouts, data


def _specified_forces(mech: Mechanism, links: list, internal_forces) -> tuple[list[tuple[int, int]], list[float]]:
    names = [link.name for link in links]
    specified, values = [], []
    for name, forces in (internal_forces or {}).items():
        if name not in names:
            raise MechanismError(f"/internal_forces/{name}", f"no link named '{name}' (links: {', '.join(names)})")
        if not isinstance(forces, dict) or not forces or not set(forces) <= {"h", "v"}:
            raise MechanismError(f"/internal_forces/{name}", 'expected {"h": value} and/or {"v": value}')
        for component, value in forces.items():
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
                raise MechanismError(f"/internal_forces/{name}/{component}", "expected a finite number")
            specified.append((names.index(name), 0 if component == "h" else 1))
            values.append(float(value) * mech.nd_per_doc("force"))
    return specified, values


def _unknown_loads(mech: Mechanism, unknown_loads) -> list[int]:
    indices = []
    for k, pointer in enumerate(unknown_loads or []):
        index = mech.parameter_index(pointer)
        if not pointer.startswith("/loads/") or mech.parameters[index].kind not in ("force", "moment"):
            raise MechanismError(f"/unknown_loads/{k}", f"'{pointer}' is not a force or moment component of a load")
        if index in indices:
            raise MechanismError(f"/unknown_loads/{k}", f"'{pointer}' is listed twice")
        indices.append(index)
    return indices


def _report_links(mech: Mechanism, values: dict[str, float], result: LinkInverseResult) -> None:
    for link in invertible(mech.structure):
        base = f"elements.{link.name}"
        nodes = range(link.intervals + 1)
        result.links[link.name] = {
            **{q_name: values[f"{base}.{q_name}"] for q_name in ("h", "v", "M_start", "M_end", "energy")},
            "u": [k / link.intervals for k in nodes],
            "eta": [values[f"{base}.eta.{k}"] * mech.nd_per_doc("angle") for k in nodes],  # rad
            "x0": [values[f"{base}.x0.{k}"] for k in nodes],
            "y0": [values[f"{base}.y0.{k}"] for k in nodes],
        }
    for body in mech.structure.bodies:
        result.bodies[body] = {q_name: values[f"bodies.{body}.{q_name}"] for q_name in ("x0", "y0", "rotation")}
