"""A modes report in document units: per mode its frequency, kind, effective masses along x and
y, the share of its kinetic energy in each body and element, and its shape.

Shapes are mass-normalized in SI (phi^T M phi = 1 with M in kg, kg m and kg m^2), then given in
the document's length and angle units: the bodies' coordinates, and the displacement of each
element's mass points (its quadrature points) from where they stand. With the shapes, the
state's drawing: each drawn element's centre line (`lines`) and each body where it stands,
whether it is fixed, and which element ends it carries (`bodies`), so that a figure draws the
bodies with the elements (service.vibration.figures)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from flexmech.models import Mechanism
from flexmech.service.vibration.modes import MechanismModes

SHARE_SHOWN = 1e-4  # energy shares below this are left out of a mode's list


def modes_report(mech: Mechanism, found: MechanismModes, z: np.ndarray, shapes: bool = True) -> dict[str, Any]:
    system, eigen = found.system, found.eigen
    lines = _centre_line_modes(mech, found, z) if shapes else None
    mass_unit = mech.doc_unit("mass")
    mass_doc = mech.scales.of("mass") / mech.doc_factor("mass")  # document mass units per nondimensional
    to_si = 1.0 / math.sqrt(mech.scales.of("energy"))  # nondimensional normalization to SI's
    M = system.M
    total = system.total_mass * mass_doc
    modes = []
    for k, (value, kind) in enumerate(zip(eigen.omega_squared, eigen.kinds)):
        phi = eigen.shapes[:, k]
        omega = math.sqrt(abs(value)) if kind != "rigid" else 0.0
        participation = system.uniform.T @ phi
        effective = participation**2 * mass_doc
        energy = float(phi @ M @ phi)
        shares = {owner: float(phi @ m @ phi) / energy for owner, m in zip(system.owners, system.masses)}
        mode: dict[str, Any] = {
            "mode": k + 1,
            "kind": kind,
            "omega": omega,
            "frequency": omega / (2 * math.pi) if kind == "elastic" else None,
            "period": 2 * math.pi / omega if kind == "elastic" and omega > 0 else None,
            "omega_squared": float(value),
            "effective_mass": {"x": float(effective[0]), "y": float(effective[1])},
            "effective_mass_fraction": {
                "x": float(effective[0] / total) if total > 0 else None,
                "y": float(effective[1] / total) if total > 0 else None,
            },
            "energy_shares": {
                owner: share
                for owner, share in sorted(shares.items(), key=lambda item: -item[1])
                if share >= SHARE_SHOWN
            },
        }
        if shapes and lines is not None:
            mode["shape"] = {**_shape(mech, system, phi * to_si), "lines": _lines(mech, lines[1][k] * to_si)}
        modes.append(mode)
    return {
        "coordinates": system.coordinates_set,
        "unknowns": len(system.coordinates),
        "available": eigen.available,
        "symmetric": eigen.symmetric,
        "total_mass": total,
        "total_mass_unit": mass_unit,
        "modes": modes,
        "points": _points(mech, system) if shapes else {},
        "lines": _lines(mech, lines[0]) if lines is not None else {},
        "bodies": _bodies(mech, z) if shapes else {},
        "units": {
            "omega": "rad/s",
            "frequency": "Hz",
            "period": "s",
            "effective_mass": mass_unit,
            "effective_mass_fraction": "relative",
            "energy_shares": "relative",
            "omega_squared": "rad^2/s^2",
            "angle": mech.doc_unit("angle"),
            "shape": f"{mech.doc_unit('length')} and {mech.doc_unit('angle')}, mass-normalized in SI",
        },
    }


def _shape(mech: Mechanism, system, phi: np.ndarray) -> dict[str, Any]:
    """The mode's bodies' coordinates and its elements' mass points' displacements (document units)."""
    length = mech.nd_per_doc("length")
    bodies: dict[str, list[float]] = {}
    for k, (b, c) in enumerate(mech.structure.free[: system.n_body]):
        name = mech.structure.bodies[b]
        row = bodies.setdefault(name, [0.0, 0.0, 0.0])
        row[c] = float(phi[k] / (length if c < 2 else mech.nd_per_doc("angle")))
    moved = (system.point_jacobian @ phi).reshape(-1, 2) / length
    elements: dict[str, list[list[float]]] = {}
    for owner, (dx, dy) in zip(system.point_owners, moved):
        elements.setdefault(owner, []).append([float(dx), float(dy)])
    return {"bodies": bodies, "elements": elements}


def _centre_line_modes(mech: Mechanism, found: MechanismModes, z: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
    """The drawn centre lines at the state (document units), and each mode's displacement of
    them (nondimensional modal amplitude): CasADi's forward derivative of the drawing along the
    mode over the residual form's unknowns."""
    from flexmech.service.vibration.sensitivity import state_vectors

    p = mech.p()
    K = np.asarray(mech.graphs.residual_and_tangent(z, p)[1], dtype=float)
    shapes = mech.graphs.shapes
    rest = [np.asarray(out, dtype=float) for out in shapes(z, p)]
    along = shapes.forward(1)
    scale = mech.scales.length / mech.doc_factor("length")
    moved = []
    for k in range(found.eigen.shapes.shape[1]):
        v, _ = state_vectors(found, K, k)
        moved.append(np.asarray(along(z, p, *rest, v, np.zeros(len(p)))[0], dtype=float) * scale)
    return rest[0] * scale, moved


def _lines(mech: Mechanism, lines: np.ndarray) -> dict[str, list[list[float]]]:
    """Per drawn element, its centre line's points [[x, y], ...]."""
    return {
        name: lines[:, first : first + columns].T.tolist() for name, first, columns, _, _ in mech.graphs.shape_segments
    }


def _bodies(mech: Mechanism, z: np.ndarray) -> dict[str, dict[str, Any]]:
    """Per body: its reference point at the state [x, y] (document length units), whether it is
    fixed, and the element ends it carries ([element, "start" | "end"], the ends of `lines`)."""
    from flexmech.service.units import outputs_in_doc_units

    outputs = outputs_in_doc_units(mech, mech.graphs.outputs(z, mech.p()))
    structure = mech.structure
    bodies: dict[str, dict[str, Any]] = {
        name: {
            "reference": [outputs[f"bodies.{name}.x"], outputs[f"bodies.{name}.y"]],
            "fixed": all(v is not None for v in structure.prescribed[b]),
            "ends": [],
        }
        for b, name in enumerate(structure.bodies)
    }
    for element, _, _, start, end in mech.graphs.shape_segments:
        bodies[structure.bodies[start]]["ends"].append([element, "start"])
        bodies[structure.bodies[end]]["ends"].append([element, "end"])
    return bodies


def _points(mech: Mechanism, system) -> dict[str, list[list[float]]]:
    """Where each element's mass points stand (document length units)."""
    length = mech.nd_per_doc("length")
    out: dict[str, list[list[float]]] = {}
    for owner, (x, y) in zip(system.point_owners, system.points.T):
        out.setdefault(owner, []).append([float(x / length), float(y / length)])
    return out
