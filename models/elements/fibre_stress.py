"""The outer-fibre bending stress along a beam element's drawn centre line, from a solved state:
what the families' optional hook `stress_along` computes for the drawing
(service.drawings.stresses). Numbers here are plain floats, nondimensional like the graphs'.

A beam without distributed load carries a constant internal force n (what the part beyond a
section exerts on the part before it: at the end, the end body's force on the element), and
the moment balance of the part between a section at p and the start gives

    M(p) = M_end + (p_end - p) x n = M_start + n x (p - p_start)

(x: the 2D cross product, a x b = a_x b_y - a_y b_x; the moment balance of a slice, m' = n x r',
integrated). For a link by shooting these are the very moments it integrates. The stress at the outer fibre is
sigma(p) = |M(p)| c / I(u). The axial part N / A is left out, as the elements' own
stress_start, stress_end and stress_max leave it out: the drawing and the outputs tables
report one quantity.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from flexmech.models.documents.sections import SectionTopology, section_properties


def number(value) -> float:
    """A float of a number built by the symbolic helpers over numeric parameters (a float, a
    DM or a constant SX)."""
    if isinstance(value, ca.SX):
        value = ca.evalf(value)
    return float(value)


def section_fibres(P, section: SectionTopology, us) -> np.ndarray | None:
    """c / I(u) at each u (nondimensional), or None for a section without an outer fibre (a
    general section without c). P: models.graph.context.Params over numeric parameters."""
    fibre = section_properties(P, section).fibre
    if fibre is None:
        return None
    u = ca.SX.sym("u")
    along = ca.Function("fibre", [u], [fibre(u)])  # one call for every u: a trace draws hundreds of states
    return np.asarray(along(np.asarray(us, dtype=float).reshape(1, -1)), dtype=float).ravel() * np.ones(len(us))


def moment_along(points: np.ndarray, m_start: float, force: np.ndarray) -> np.ndarray:
    """M(p) = M_start + n x (p - p_start) at each point (n, 2) of a centre line (its first is the
    start), for an element without distributed load."""
    d = np.asarray(points, dtype=float) - np.asarray(points[0], dtype=float)
    return m_start + force[0] * d[:, 1] - force[1] * d[:, 0]


def link_stresses(P, topology, outputs: dict[str, float], points: np.ndarray, us) -> np.ndarray | None:
    """The stress at each point of a link (either discretization) at the u of each, from its
    outputs h, v (the internal force) and M_start; None where its section has no outer fibre,
    or where it carries its own weight (a distributed load: the formula above does not hold)."""
    if getattr(topology, "weighs", False) and "/gravity/0" in P:
        return None
    fibres = section_fibres(P, topology.section, us)
    if fibres is None or any(outputs.get(k) is None for k in ("h", "v", "M_start")):
        return None
    force = np.array([outputs["h"], outputs["v"]])
    return np.abs(moment_along(points, outputs["M_start"], force)) * fibres
