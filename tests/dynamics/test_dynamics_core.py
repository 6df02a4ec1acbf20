"""Time simulation's core (models.graph.dynamics, service.dynamics): a clamped steel rod (seed 002
Table 4.1: 1.11 x 0.0127 x 0.0032 m, E = 200 GPa, rho = 7850 kg/m^3) by cubic elements.
Its first natural period equals Euler-Bernoulli's 2 pi / (1.8751^2 sqrt(EI / (rho A L^4)));
released in its first mode it rings with that period; average-acceleration Newmark keeps
the energy of the small (linear) vibration; both schemes converge at second order in the
step; a heavily damped rod under a tip force settles to the static equilibrium."""

from __future__ import annotations

import numpy as np
import pytest

from flexmech.models import compile_mechanism, load_document
from flexmech.service.dynamics.integrate import integrate
from flexmech.service.dynamics.modes import natural_modes
from flexmech.service.dynamics.schemes import generalized_alpha, newmark
from flexmech.service.solvers.energy import minimize_energy

L, B, H, RHO, E = 1.11, 0.0127, 0.0032, 7850.0, 2e11
EI, RHO_A = E * B * H**3 / 12, RHO * B * H
PERIOD = 2 * np.pi / (1.8751**2 * np.sqrt(EI / (RHO_A * L**4)))  # 0.4722 s


def rod(intervals: int = 4, force: float = 0.0) -> dict:
    return {
        "units": {"length": "m", "force": "N", "angle": "rad", "mass": "kg"},
        "materials": {"steel": {"E": E, "G": 8e10, "density": RHO}},
        "sections": {"rod": {"b": B, "h": H}},
        "bodies": {"clamp": {"fixed": True, "position": [0, 0]}, "tip": {"position": [L, 0]}},
        "elements": {
            "rod": {
                "type": "link",
                "from": "clamp",
                "to": "tip",
                "length": L,
                "material": "steel",
                "section": "rod",
                "discretization": "elements",
                "intervals": intervals,
            }
        },
        "loads": {"hold": {"type": "force", "body": "tip", "force": [0, force]}},
    }


def first_mode(mech, amplitude: float) -> np.ndarray:
    """The rod's first mode shape, its tip deflection `amplitude` (m)."""
    n, m = len(mech.graphs.energy_form.unknowns), mech.graphs.energy_form.n_multipliers
    shape = natural_modes(mech.structure, mech.p(), np.zeros(n), np.zeros(m)).shapes[:, 0]
    return shape / shape[1] * amplitude * mech.nd_per_doc("length")


def tip_y(history) -> np.ndarray:
    return np.array([x[1] for x in history.x])  # the free coordinates tip.x, tip.y, tip.angle come first


def down_crossings(times: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.array(
        [
            times[i] - y[i] * (times[i + 1] - times[i]) / (y[i + 1] - y[i])
            for i in range(len(y) - 1)
            if y[i] > 0 >= y[i + 1]
        ]
    )


def test_the_first_period_is_euler_bernoullis():
    mech = compile_mechanism(load_document(rod(4)))
    n, m = len(mech.graphs.energy_form.unknowns), mech.graphs.energy_form.n_multipliers
    omega = natural_modes(mech.structure, mech.p(), np.zeros(n), np.zeros(m)).omegas[0]
    assert abs(2 * np.pi / omega / PERIOD - 1) < 1e-4
    history = integrate(
        mech.structure,
        mech.p(),
        first_mode(mech, 1e-4),
        np.zeros(n),
        2.2 * PERIOD,
        PERIOD / 200,
        generalized_alpha(0.9),
    )
    assert history.status == "finished"
    periods = np.diff(down_crossings(np.array(history.times), tip_y(history)))
    assert len(periods) == 1 and abs(periods[0] / PERIOD - 1) < 1e-3


def test_average_acceleration_keeps_the_energy_of_a_small_vibration():
    """Ten periods at 100 steps each, tip amplitude 10 um: kinetic plus strain energy stays
    within 1e-8 of its start."""
    mech = compile_mechanism(load_document(rod(4)))
    x0 = first_mode(mech, 1e-5)
    history = integrate(mech.structure, mech.p(), x0, np.zeros_like(x0), 10 * PERIOD, PERIOD / 100, newmark())
    energy = np.array(history.kinetic) + np.array(history.potential)
    assert history.status == "finished" and energy[0] > 0
    assert np.abs(energy / energy[0] - 1).max() < 1e-8


@pytest.mark.parametrize("scheme", [newmark(), generalized_alpha(0.8)], ids=["newmark", "generalized_alpha"])
def test_the_schemes_converge_at_second_order_in_the_step(scheme):
    """The tip's deflection after 0.6 period, released from 5 cm in the first mode, at steps
    T/25, T/50 and T/100 against T/800: each halving divides the error by 4 (within 0.3)."""
    mech = compile_mechanism(load_document(rod(4)))
    x0 = first_mode(mech, 0.05)

    def at_end(steps: int) -> float:
        history = integrate(mech.structure, mech.p(), x0, np.zeros_like(x0), 0.6 * PERIOD, 0.6 * PERIOD / steps, scheme)
        assert history.status == "finished", history.message
        return tip_y(history)[-1]

    reference = at_end(480)
    errors = [abs(at_end(steps) - reference) for steps in (15, 30, 60)]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 2) < 0.3), (errors, orders)


def test_a_damped_rod_settles_to_the_static_equilibrium():
    """A 2 N tip force from rest, mass-proportional damping 40 1/s (above critical for the
    first mode): after 3 s the state is the minimum of the energy to 1e-6."""
    mech = compile_mechanism(load_document(rod(4, force=2.0)))
    static = mech.graphs.energy_form.x_of_state(minimize_energy(mech).z)
    n = len(static)
    history = integrate(
        mech.structure, mech.p(), np.zeros(n), np.zeros(n), 3.0, 0.01, generalized_alpha(0.8), damping=40.0
    )
    assert history.status == "finished"
    assert np.abs(history.x[-1] - static).max() < 1e-6 * np.abs(static).max()


@pytest.mark.parametrize("degree, intervals", [(1, (2, 4, 8)), (2, (2, 4, 8)), (3, (1, 2, 4))])
def test_the_first_frequency_converges_at_twice_the_degree_in_space(degree, intervals):
    """Rotation elements of degree p (mass lumped at their quadrature points): the first
    natural frequency's error against 16 elements of degree 4 falls as h^(2p)."""

    def first_omega(count: int, p: int) -> float:
        document = rod(count)
        document["elements"]["rod"]["degree"] = p
        mech = compile_mechanism(load_document(document))
        n, m = len(mech.graphs.energy_form.unknowns), mech.graphs.energy_form.n_multipliers
        return natural_modes(mech.structure, mech.p(), np.zeros(n), np.zeros(m)).omegas[0]

    reference = first_omega(16, 4)
    errors = np.array([abs(first_omega(count, degree) / reference - 1) for count in intervals])
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(np.abs(orders - 2 * degree) < 0.35), (errors, orders)
