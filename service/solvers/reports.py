"""Pieces of every report: JSON-able values, units of outputs and coordinates, the tangent
stiffness as data. Reports are in the document's units and say which unit goes with which
number."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from flexmech.models import Mechanism
from flexmech.service.solvers.stiffness import tangent_stiffness


def plain(obj: Any) -> Any:
    """JSON-able copy: numpy scalars and arrays to Python numbers and lists, non-finite to None."""
    if isinstance(obj, dict):
        return {str(k): plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        if obj and all(type(v) is float for v in obj):  # a curve of floats (a simulation's: 20k numbers)
            return list(obj) if math.isfinite(sum(obj)) else [v if math.isfinite(v) else None for v in obj]
        return [plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind == "f" and np.isfinite(obj).all():
            return obj.tolist()  # floats throughout: nothing to replace (long curves, quickly)
        return plain(obj.tolist())
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        value = float(obj)
        return value if math.isfinite(value) else None
    return obj


def stiffness_dict(mech: Mechanism, z) -> dict:
    kt = tangent_stiffness(mech, z)
    return {
        "coordinates": kt.coordinates,
        "row_units": kt.row_units,
        "column_units": kt.column_units,
        "K": kt.K,
        "terms": kt.terms,
        "symmetric": kt.symmetric,
    }


def output_units(mech: Mechanism) -> dict[str, str]:
    g = mech.graphs
    return {name: mech.doc_unit(kind) for name, kind in zip(g.output_names, g.output_kinds)}


def coordinate_units(mech: Mechanism) -> dict[str, str]:
    kinds = ("length", "length", "angle")
    return {name: mech.doc_unit(kinds[c]) for name, (_, c) in zip(mech.free_coordinates, mech.structure.free)}
