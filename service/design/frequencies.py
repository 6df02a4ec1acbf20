"""Natural frequencies and frequency responses in the design NLP (service.design.nlp): each
frequency's scales, its mode's start from a modes run at the start design, and the check of the
optimum by a fresh modes run; each response's factor to document units, its amplitude's start
and its value at a state.

Scales: omega_0^2, the start's omega^2, so the unknown l = omega^2 / omega_0^2 is near one;
m_0, the modal mass v.M_z v of the start's mode scaled to a largest entry of one, so the mode's
entries stay near one whatever the units."""

from __future__ import annotations

import numpy as np

from flexmech.models import MechanismError
from flexmech.service.design.problem import DesignProblem, OutputRef
from flexmech.service.vibration.sensitivity import state_mode

AGREEMENT = 1e-6  # relative: the NLP's frequency and a fresh modes run's at the optimum


def _mode(problem: DesignProblem, ref: OutputRef, z: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, float]:
    try:
        return state_mode(problem.mechanism, z, p, ref.index)
    except MechanismError as exc:
        if exc.pointer == "/count":
            raise MechanismError(ref.name, f"'{ref.name}': {exc.problem}") from None
        raise


def frequency_value(problem: DesignProblem, ref: OutputRef, z: np.ndarray, p: np.ndarray) -> float:
    """The frequency (Hz) of a modes run at (z, p)."""
    _, omega_squared = _mode(problem, ref, z, p)
    return float(np.sqrt(max(omega_squared, 0.0)) / (2 * np.pi))


def eigen_scales(problem: DesignProblem, frequencies, states, ps) -> np.ndarray:
    """(omega_0^2, m_0) per frequency, from the start's states (the undeformed one where the
    start's did not converge)."""
    mass = _mass(problem)
    scales = []
    for ref in frequencies:
        status, z = states[ref.case]
        z = z if status == "converged" else np.zeros(len(z))
        v, omega_squared = _mode(problem, ref, z, ps[ref.case])
        v = v / np.abs(v).max()
        scales += [omega_squared if omega_squared > 0 else 1.0, float(v @ mass(z, ps[ref.case]) @ v)]
    return np.array(scales, dtype=float)


def eigen_guess(problem: DesignProblem, frequencies, zs, ps, scales: np.ndarray) -> np.ndarray:
    """Each frequency's unknowns [v; l] at the states zs: the k-th mode, v.M_z v = m_0."""
    mass = _mass(problem)
    parts = []
    for j, ref in enumerate(frequencies):
        z, p = zs[ref.case], ps[ref.case]
        v, omega_squared = _mode(problem, ref, z, p)
        v = v * np.sqrt(scales[2 * j + 1] / float(v @ mass(z, p) @ v))
        parts.append(np.concatenate([v, [max(omega_squared, 0.0) / scales[2 * j]]]))
    return np.concatenate(parts) if parts else np.zeros(0)


def unknown_bounds(frequencies, n_state: int, responses: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The modes' bounds (the vectors free, omega^2 / omega_0^2 positive), then the responses'
    (free)."""
    lower = np.concatenate(
        [np.append(np.full(n_state, -np.inf), 1e-9) for _ in frequencies] + [np.full(2 * n_state * responses, -np.inf)]
    )
    upper = np.full(len(lower), np.inf)
    return lower, upper


def disagreements(problem: DesignProblem, frequencies, x: np.ndarray, n_states: int, zs, ps) -> list[str]:
    """Frequencies whose NLP mode is not the k-th one of a fresh modes run at the optimum."""
    found = []
    n = len(zs[0]) + 1
    for j, ref in enumerate(frequencies):
        tracked = x[n_states + j * n : n_states + (j + 1) * n]
        fresh = frequency_value(problem, ref, zs[ref.case], ps[ref.case])
        followed = _followed(problem, ref, tracked[:-1], zs, ps)
        if abs(followed - fresh) > AGREEMENT * max(fresh, 1e-300):
            found.append(
                f"{ref.name}: the optimizer followed a mode at {followed:.6g} Hz, but the mode "
                f"{ref.index + 1} of a fresh modes run at the optimum is at {fresh:.6g} Hz (modes crossed on "
                "the way): try other starts, or constrain the neighbouring frequencies too"
            )
    return found


def _followed(problem: DesignProblem, ref: OutputRef, v: np.ndarray, zs, ps) -> float:
    """The Rayleigh quotient of the NLP's mode at the optimum's state (Hz)."""
    z, p = zs[ref.case], ps[ref.case]
    K = np.asarray(problem.mechanism.graphs.residual_and_tangent(z, p)[1], dtype=float)
    M = _mass(problem)(z, p)
    omega_squared = float(v @ K @ v) / float(v @ M @ v)
    return float(np.sqrt(max(omega_squared, 0.0)) / (2 * np.pi))


def _mass(problem: DesignProblem):
    from flexmech.models.graph.modal import state_mass

    function = state_mass(problem.mechanism.structure)
    return lambda z, p: np.asarray(function(z, p), dtype=float)


def _response_system(problem: DesignProblem, ref: OutputRef, z: np.ndarray, p: np.ndarray) -> np.ndarray:
    """X = (K_T - omega^2 M + i omega (alpha M + beta K_T))^-1 f over z, f the load's unit force."""
    graphs = problem.mechanism.graphs
    K = np.asarray(graphs.residual_and_tangent(z, p)[1], dtype=float)
    M = _mass(problem)(z, p)
    pushed = p.copy()
    pushed[ref.input] += 1
    force = np.asarray(graphs.residual(z, p), dtype=float).ravel() - np.asarray(graphs.residual(z, pushed)).ravel()
    omega = 2 * np.pi * ref.frequency
    damping = problem.spec.damping
    A = K - omega**2 * M + 1j * omega * (damping.mass * M + damping.stiffness * K)
    return np.linalg.solve(A, force)


def response_factor(problem: DesignProblem, ref: OutputRef) -> float:
    mech = problem.mechanism
    return mech.nd_per_doc(mech.parameters[ref.input].kind) / mech.nd_per_doc(ref.kind)


def response_value(problem: DesignProblem, ref: OutputRef, z: np.ndarray, p: np.ndarray) -> float:
    """The response's amplitude at (z, p), in its unit."""
    from flexmech.service.vibration.harmonic import output_derivatives

    row = np.asarray(output_derivatives(problem.mechanism.structure)[0](z, p), dtype=float)[ref.index]
    return float(abs(row @ _response_system(problem, ref, z, p)) * response_factor(problem, ref))


def response_scales(problem: DesignProblem, responses) -> np.ndarray:
    """The NLP parameters of the responses: a factor each, then alpha and beta."""
    if not responses:
        return np.zeros(0)
    damping = problem.spec.damping
    return np.array([*(response_factor(problem, ref) for ref in responses), damping.mass, damping.stiffness])


def response_guess(problem: DesignProblem, responses, zs, ps) -> np.ndarray:
    """Each response's unknowns [Re X; Im X] at the states zs."""
    parts = []
    for ref in responses:
        X = _response_system(problem, ref, zs[ref.case], ps[ref.case])
        parts.append(np.concatenate([X.real, X.imag]))
    return np.concatenate(parts) if parts else np.zeros(0)


def vibration_start(problem: DesignProblem, nlp, P: np.ndarray, zs, ps) -> np.ndarray:
    """The frequencies' modes and the responses' amplitudes at the start states zs (the NLP's
    unknowns after the states); their scales are the tail of the NLP parameters P."""
    n_responses = len(nlp.responses) + 2 if nlp.responses else 0
    scales = P[len(P) - n_responses - 2 * len(nlp.frequencies) : len(P) - n_responses]
    return np.concatenate(
        [eigen_guess(problem, nlp.frequencies, zs, ps, scales), response_guess(problem, nlp.responses, zs, ps)]
    )
