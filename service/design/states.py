"""The states of a design problem's load cases: each case's parameters at a design, the
equilibrium each reaches when loaded gradually (the branch a real mechanism follows, where
an optimizer may land on another), and every case's outputs at the NLP's unknowns."""

from __future__ import annotations

import re

import numpy as np

from flexmech.models import Mechanism
from flexmech.service.design.frequencies import frequency_value, response_value
from flexmech.service.design.problem import DesignProblem, OutputRef
from flexmech.service.solvers.equilibrium import newton
from flexmech.service.solvers.newton import NewtonOptions


def case_params(problem: DesignProblem, design: np.ndarray) -> list[np.ndarray]:
    """Nondimensional parameters of every case for a design (document units)."""
    ps = []
    for p in problem.case_p:
        p = p.copy()
        p[list(problem.slots)] = design * problem.nd_per_doc
        ps.append(p)
    return ps


LOAD_MAGNITUDE = re.compile(r"^(/loads/[^/]+/(force/[01]|moment|dx|dy|rotation)|/gravity/[01])$")
LOAD_STEPS = 8


def _load_slots(mech: Mechanism) -> list[int]:
    return [k for k, param in enumerate(mech.parameters) if LOAD_MAGNITUDE.match(param.pointer)]


def loaded_state(
    mech: Mechanism, p: np.ndarray, steps: int = LOAD_STEPS, options: NewtonOptions = NewtonOptions(max_iterations=100)
) -> tuple[str, np.ndarray]:
    """The equilibrium the mechanism reaches when its loads (forces, moments, prescribed
    motions) grow from zero in equal steps, each from the previous state: the branch a real
    mechanism follows, where a single Newton solve (or an optimizer) may find another."""
    slots = _load_slots(mech)
    z = np.zeros(mech.n_free)
    for k in range(1, steps + 1):
        pk = p.copy()
        pk[slots] = p[slots] * k / steps

        result = newton(mech, pk, z, options)
        z = result.z
        if result.status != "converged":
            return result.status, z
    return "converged", z


def equilibria(problem: DesignProblem, design: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """(status, z) of every case at a design (document units), reached by loading."""
    return [loaded_state(problem.mechanism, p) for p in case_params(problem, design)]


def same_state(a: np.ndarray, b: np.ndarray) -> bool:
    return bool(np.abs(a - b).max(initial=0.0) <= 1e-6 * (1 + np.abs(b).max(initial=0.0)))


def polished_states(problem: DesignProblem, design: np.ndarray, zs: list[np.ndarray]):
    """The states the NLP found, polished by Newton where they are the ones the mechanism
    reaches when loaded at that design (an optimizer can land on another equilibrium branch,
    e.g. a snapped-through shape), and whether every case's is."""
    loaded = equilibria(problem, design)
    on_branch = all(s == "converged" and same_state(z, zc) for (s, z), zc in zip(loaded, zs))
    zs = [z if s == "converged" and same_state(z, zc) else zc for (s, z), zc in zip(loaded, zs)]
    return zs, on_branch


def case_outputs(problem: DesignProblem, x: np.ndarray) -> dict[str, dict[str, float]]:
    from flexmech.service.units import outputs_in_doc_units

    mech: Mechanism = problem.mechanism
    n_design = len(problem.slots)
    n_cases = len(problem.case_p)
    zs = np.split(x[n_design : n_design + problem.mechanism.structure.n_unknowns * n_cases], n_cases)
    ps = case_params(problem, x[:n_design] * problem.scale)
    return {
        name: outputs_in_doc_units(mech, mech.graphs.outputs(z, p)) for name, z, p in zip(problem.case_names, zs, ps)
    }


def output_value(problem: DesignProblem, ref: OutputRef, z: np.ndarray, p: np.ndarray) -> float:
    """An output's nondimensional value at a state."""
    g = problem.mechanism.graphs
    if ref.source == "yield":
        return 0.0  # scaled by its bounds alone: a far start's ln(1e-17) would make its bound loose
    if ref.sigmas:
        from flexmech.service.design.robust import robust_value

        return robust_value(problem.mechanism.structure, ref, z, p)
    if ref.source == "parameter":
        return float(p[ref.index])
    if ref.source == "stiffness":
        K = np.asarray(g.residual_and_tangent(z, p)[1])
        return float(1 / np.linalg.inv(K)[ref.index, ref.index])
    if ref.source == "frequency":
        return frequency_value(problem, ref, z, p)
    if ref.source == "response":
        return response_value(problem, ref, z, p)
    return float(np.asarray(g.outputs(z, p)).ravel()[ref.index])
