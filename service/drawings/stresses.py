"""Stresses on the drawing (service.drawings.drawing): the outer-fibre bending stress at each
drawn point of every beam element's deformed centre line in a solved state, in the document's
stress unit, and each element's allowable stress (its material's `stress_limit`).

Each family computes its own, through its optional hook `stress_along`
(models.elements.fibre_stress has the formula, sigma = |M| c / I with M(p) = M_end +
(p_end - p) x n): curved beams from their closed-form balance, links of either
discretization from their internal force and start moment. An element is left out where its
family has no hook (pins, sliders, springs), its section no outer fibre (a general section
without c), or it carries its own weight under gravity (a distributed load); so is every
element of a state given without its outputs.
"""

from __future__ import annotations

import numpy as np

from flexmech.models import Mechanism
from flexmech.models.elements import FAMILIES
from flexmech.models.graph.collector import check_value
from flexmech.models.graph.context import Params
from flexmech.models.units import quantity_to_si


def _stressed(mech: Mechanism):
    """The elements whose family tells stresses, with the hook."""
    for topology in mech.structure.elements:
        hook = getattr(FAMILIES.of(topology), "stress_along", None)
        if hook is not None:
            yield topology, hook


def _own_outputs(mech: Mechanism, outputs: dict) -> dict[str, dict[str, float]]:
    """Per element, its outputs (elements.<name>.<quantity>, document units) nondimensional, by
    quantity."""
    own: dict[str, dict[str, float]] = {}
    for name, kind in zip(mech.graphs.output_names, mech.graphs.output_kinds):
        value = outputs.get(name)
        if value is None or not name.startswith("elements."):
            continue
        element, quantity = name.removeprefix("elements.").rsplit(".", 1)
        own.setdefault(element, {})[quantity] = float(value) * mech.nd_per_doc(kind)
    return own


def frame_stresses(mech: Mechanism, p: np.ndarray, outputs: dict, deformed: np.ndarray) -> dict[str, list[float]]:
    """Per element, the stress at each point of its deformed centre line (document stress units),
    for a state whose outputs (document units) and deformed samples (2 x samples, nondimensional,
    as graphs.shapes gives them) are given."""
    own = _own_outputs(mech, outputs) if outputs else {}
    if not own:
        return {}
    P, to_doc = Params(mech.structure, np.asarray(p, dtype=float)), 1.0 / mech.nd_per_doc("stress")
    columns = {name: (first, count) for name, first, count, _, _ in mech.graphs.shape_segments}
    found = {}
    for topology, hook in _stressed(mech):
        if topology.name not in columns or topology.name not in own:
            continue
        first, count = columns[topology.name]
        along = hook(P, topology, own[topology.name], deformed[:, first : first + count].T)
        if along is not None:
            found[topology.name] = [float(v) * to_doc for v in along]
    return found


def stress_limits(mech: Mechanism) -> dict[str, float]:
    """Per element that tells stresses, its material's allowable stress (document stress units),
    where the material gives one; checked as the document's numbers are (a MechanismError names
    the field)."""
    unit, factor = mech.doc_unit("stress"), mech.doc_factor("stress")
    limits = {}
    for topology, _ in _stressed(mech):
        material = getattr(topology, "material", None)
        spec = mech.document.materials.get(material) if material is not None else None
        given = getattr(spec, "stress_limit", None)
        if given is None:
            continue
        pointer = f"/materials/{material}/stress_limit"
        si = quantity_to_si(given, "stress", unit, pointer)
        check_value(pointer, si, "positive", unit, factor, given)
        limits[topology.name] = si / factor
    return limits
