"""Peer implementation in Exudyn of two planar flexible-beam dynamics examples of Lan (2005), ch. 4.

Install the peer with ``pip install exudyn`` (written against exudyn 1.13).

Both examples use 2-node ``ObjectBeamGeometricallyExact2D`` elements (Simo/Reissner beam with linear
interpolation, one-point (midpoint) integration of the strains, consistent mass matrix) on
``NodeRigidBody2D`` nodes (rotary inertia rho*I per length; shear stiffness kappa*G*A with kappa = 1
for the rod, 0.9 for the four-bar), and Exudyn's generalized-alpha integrator with spectral radius
``rho_inf``, a fixed step (no step adaptation), modified Newton and the EigenSparse linear solver
(faster here than the default dense one). No gravity.

* ``rod_free_vibration`` (Example I.1): a clamped steel rod is first bent by a tip force
  F = (7.919276, 10.998155) N in a separate *static* model (``SolveStatic`` with a load ramp). The
  nodal displacements of that solution become the initial coordinates of a second, fresh dynamic
  model without any load, which is released from rest at t = 0. Measures: tip path, period (mean
  time between downward zero crossings of tip_y) and the drift of kinetic + strain energy.
* ``four_bar`` (Example II.2): crank, coupler and follower as flexible links joined by pins
  (``ObjectJointRevolute2D``; ground pins by coordinate constraints on the end nodes). The crank is
  driven by a piecewise linear moment M(t) at A, given as an Exudyn *symbolic* user function, so it
  is evaluated in C++ and no Python is called during the run. Measures: kinetic and strain energy,
  the input work W = trapz(M * omega_A), and the balance error max|T + U - W| / max W.

Energies: the beam element has no energy output, so every node carries two Exudyn sensors
(``Coordinates`` and ``Coordinates_t``, ``storeInternal=True``, recorded every step, no files).
After the run T and U are evaluated in numpy from these histories with the element's own
discretisation: T_e = rhoA L/6 (|v0|^2 + v0.v1 + |v1|^2) + rhoJ L/6 (w0^2 + w0 w1 + w1^2)
(consistent mass matrix of the element) and U_e = L/2 (EA g1^2 + GA g2^2 + EI k^2) at the element
midpoint, with g1 = d.r' - 1, g2 = n.r', d = (cos th, sin th), n = (-sin th, cos th), r' = (p1 - p0)/L,
th = (th0 + th1)/2 and k = (th1 - th0)/L -- the potential whose gradient is the element's internal
force, so T + U is the conserved energy of the discrete model.

Timing: ``wall_seconds`` is time.perf_counter around ``SolveDynamic`` only: it includes the solver's
initialisation (initial accelerations) and the C++ sensors (about 10-15 % of the run), but not model
building, the static solve (both in ``setup_seconds``) or the numpy post-processing. No Python code
runs during the timed simulation. Renderer, solution files and solver output are off.
Newton tolerances: Exudyn's defaults (relative 1e-8, absolute 1e-10) for the rod; relative 1e-6,
absolute 1e-5 (N) for the four-bar, whose residual stalls at round-off level ~1e-6 N.
"""

from __future__ import annotations

import time

import exudyn as exu
import exudyn.itemInterface as eii
import numpy as np
from exudyn.advancedUtilities import CreateSymbolicUserFunction

OV = exu.OutputVariableType


class _Link:
    """A straight flexible link of n GeometricallyExactBeam2D elements from p0 to p1."""

    def __init__(self, mbs, p0, p1, n, E, G, rho, A, I, kappa=1.0, init=None):
        p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
        d = p1 - p0
        self.length_e = np.linalg.norm(d) / n
        self.angle = np.arctan2(d[1], d[0])
        self.EA, self.GA, self.EI = E * A, kappa * G * A, E * I
        self.rhoA, self.rhoJ = rho * A, rho * I
        self.ref = np.array([[*(p0 + d * i / n), self.angle] for i in range(n + 1)])
        self.nodes = []
        for i, ref in enumerate(self.ref):
            q0 = [0.0, 0.0, 0.0] if init is None else list(init[i])
            self.nodes.append(mbs.AddNode(eii.NodeRigidBody2D(referenceCoordinates=list(ref), initialCoordinates=q0)))
        for a, b in zip(self.nodes[:-1], self.nodes[1:]):
            mbs.AddObject(
                eii.ObjectBeamGeometricallyExact2D(
                    nodeNumbers=[a, b],
                    length=self.length_e,
                    massPerLength=self.rhoA,
                    crossSectionInertia=self.rhoJ,
                    bendingStiffness=self.EI,
                    axialStiffness=self.EA,
                    shearStiffness=self.GA,
                )
            )

    def add_sensors(self, mbs):
        kw = {"writeToFile": False, "storeInternal": True}
        self.s_q = [
            mbs.AddSensor(eii.SensorNode(nodeNumber=n, outputVariableType=OV.Coordinates, **kw)) for n in self.nodes
        ]
        self.s_v = [
            mbs.AddSensor(eii.SensorNode(nodeNumber=n, outputVariableType=OV.Coordinates_t, **kw)) for n in self.nodes
        ]

    def histories(self, mbs):
        """(times, q, v) with q, v of shape (steps, nodes, 3): displacement coordinates and velocities."""
        data_q = [mbs.GetSensorStoredData(s) for s in self.s_q]
        data_v = [mbs.GetSensorStoredData(s) for s in self.s_v]
        return data_q[0][:, 0], np.stack([d[:, 1:4] for d in data_q], 1), np.stack([d[:, 1:4] for d in data_v], 1)

    def energies(self, q, v):
        """Kinetic and strain energy histories of the link (see module docstring)."""
        L = self.length_e
        vt = v[:, :, :2]
        pairs = vt[:, :-1] ** 2 + vt[:, :-1] * vt[:, 1:] + vt[:, 1:] ** 2
        T = self.rhoA * L / 6 * np.sum(np.sum(pairs, axis=2), axis=1)
        w = v[:, :, 2]
        T += self.rhoJ * L / 6 * np.sum(w[:, :-1] ** 2 + w[:, :-1] * w[:, 1:] + w[:, 1:] ** 2, axis=1)
        pos = self.ref[None, :, :2] + q[:, :, :2]
        th = self.ref[None, :, 2] + q[:, :, 2]
        rp = (pos[:, 1:] - pos[:, :-1]) / L
        thm = 0.5 * (th[:, 1:] + th[:, :-1])
        c, s = np.cos(thm), np.sin(thm)
        g1 = c * rp[..., 0] + s * rp[..., 1] - 1.0
        g2 = -s * rp[..., 0] + c * rp[..., 1]
        k = (th[:, 1:] - th[:, :-1]) / L
        U = 0.5 * L * np.sum(self.EA * g1**2 + self.GA * g2**2 + self.EI * k**2, axis=1)
        return T, U


def _clamp(mbs, node, coordinates):
    """Constrain the given (displacement) coordinates of a node to zero."""
    ground = mbs.AddNode(eii.NodePointGround())
    m_ground = mbs.AddMarker(eii.MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    for c in coordinates:
        m = mbs.AddMarker(eii.MarkerNodeCoordinate(nodeNumber=node, coordinate=c))
        mbs.AddObject(eii.ObjectConnectorCoordinate(markerNumbers=[m_ground, m]))


def _pin(mbs, node_a, node_b):
    ma = mbs.AddMarker(eii.MarkerNodePosition(nodeNumber=node_a))
    mb = mbs.AddMarker(eii.MarkerNodePosition(nodeNumber=node_b))
    mbs.AddObject(eii.ObjectJointRevolute2D(markerNumbers=[ma, mb]))


def _settings(step, until, rho_inf, rel_tol=1e-8, abs_tol=1e-10):
    s = exu.SimulationSettings()
    s.solution.file.write = False
    s.solution.sensors.writePeriod = step
    s.show.computationTime = False
    s.show.statistics = False
    s.linearSolver.solverType = exu.LinearSolverType.EigenSparse  # faster than EXUdense for both examples
    ti = s.timeIntegration
    ti.verboseMode = 0
    ti.numberOfSteps = round(until / step)
    ti.endTime = until
    ti.adaptiveStep = False
    ti.generalizedAlpha.spectralRadius = rho_inf
    ti.newton.relativeTolerance = rel_tol
    ti.newton.absoluteTolerance = abs_tol
    s.staticSolver.verboseMode = 0
    return s


def _solve_dynamic(mbs, settings):
    t0 = time.perf_counter()
    ok = mbs.SolveDynamic(settings, showHints=False, showCausingItems=False)
    wall = time.perf_counter() - t0
    if not ok:
        raise RuntimeError("Exudyn dynamic solver failed")
    return wall


# ----------------------------------------------------------------------------------------------
# Example I.1: free vibration of a clamped rod released from a statically bent shape

ROD = {"L": 1.11, "b": 0.0127, "h": 0.0032, "E": 200e9, "G": 80e9, "rho": 7850.0}
ROD_TIP_FORCE = (7.919276, 10.998155)


def _rod_model(elements, init=None, tip_force=None):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    A, I = ROD["b"] * ROD["h"], ROD["b"] * ROD["h"] ** 3 / 12
    rod = _Link(mbs, (0.0, 0.0), (ROD["L"], 0.0), elements, ROD["E"], ROD["G"], ROD["rho"], A, I, init=init)
    _clamp(mbs, rod.nodes[0], (0, 1, 2))
    if tip_force is not None:
        m_tip = mbs.AddMarker(eii.MarkerNodePosition(nodeNumber=rod.nodes[-1]))
        mbs.AddLoad(eii.LoadForceVector(markerNumber=m_tip, loadVector=[*tip_force, 0.0]))
    return SC, mbs, rod


def rod_free_vibration(elements: int = 16, step: float = 1e-3, until: float = 5.0, rho_inf: float = 0.95) -> dict:
    """Example I.1 (see module docstring); returns histories, period, energy drift and timings."""
    t_setup = time.perf_counter()
    # 1) static shape under the tip force, in its own model
    _container_s, mbs_s, rod_s = _rod_model(elements, tip_force=ROD_TIP_FORCE)
    mbs_s.Assemble()
    st = _settings(step, until, rho_inf)
    st.staticSolver.numberOfLoadSteps = 20
    if not mbs_s.SolveStatic(st, showHints=False, showCausingItems=False):
        raise RuntimeError("Exudyn static solver failed")
    q_static = np.array([mbs_s.GetNodeOutput(n, OV.Coordinates) for n in rod_s.nodes])
    # 2) fresh dynamic model started from that shape, without load
    _container, mbs, rod = _rod_model(elements, init=q_static)  # keep the container alive
    rod.add_sensors(mbs)
    mbs.Assemble()
    settings = _settings(step, until, rho_inf)
    setup = time.perf_counter() - t_setup
    wall = _solve_dynamic(mbs, settings)

    times, q, v = rod.histories(mbs)
    tip = rod.ref[None, -1, :2] + q[:, -1, :2]
    kinetic, potential = rod.energies(q, v)
    energy = kinetic + potential
    y = tip[:, 1]
    down = np.nonzero((y[:-1] > 0.0) & (y[1:] <= 0.0))[0]
    crossings = times[down] + (times[down + 1] - times[down]) * y[down] / (y[down] - y[down + 1])
    period = float(np.mean(np.diff(crossings))) if len(crossings) > 1 else float("nan")
    return {
        "times": times,
        "tip_x": tip[:, 0],
        "tip_y": tip[:, 1],
        "kinetic": kinetic,
        "potential": potential,
        "wall_seconds": wall,
        "setup_seconds": setup,
        "period": period,
        "energy_drift": float(np.max(np.abs(energy / energy[0] - 1.0))),
    }


# ----------------------------------------------------------------------------------------------
# Example II.2: flexible four-bar driven by a moment at the crank

FOUR_BAR = {
    "r": 0.02,
    "rho": 7847.0,
    "E_stiff": 2.1e11,
    "E_coupler": 2.1e8,
    "kappa": 0.9,
    "A": (0.0, 0.0),
    "B": (0.5, 0.0),
    "C": (0.75, 0.9682458366),
    "D": (1.0, 0.0),
}


def drive_moment(t):
    """Drive moment at A (N m): 500 t, 100, 100 - 500 (t - 0.4), 0 on [0,.2), [.2,.4), [.4,.6), [.6,oo)."""
    t = np.asarray(t, float)
    return 500.0 * (np.clip(t, 0.0, 0.2) - np.clip(t - 0.4, 0.0, 0.2))


def _drive_moment_symbolic(mbs, t, load):
    # same ramp as drive_moment, written with Exudyn's symbolic min/max (compiled into C++ evaluation)
    esym = exu.symbolic
    return 500.0 * (esym.min(esym.max(t, 0.0), 0.2) - esym.min(esym.max(t - 0.4, 0.0), 0.2))


def four_bar(elements=(8, 16, 16), step: float = 1e-3, until: float = 1.5, rho_inf: float = 0.95) -> dict:
    """Example II.2 (see module docstring); returns energies, input work, balance error, C and timings."""
    t_setup = time.perf_counter()
    fb = FOUR_BAR
    A, I = np.pi * fb["r"] ** 2, np.pi * fb["r"] ** 4 / 4
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    links = []
    for (p0, p1), n, E in zip(
        ((fb["A"], fb["B"]), (fb["B"], fb["C"]), (fb["D"], fb["C"])),
        elements,
        (fb["E_stiff"], fb["E_coupler"], fb["E_stiff"]),
    ):
        links.append(_Link(mbs, p0, p1, n, E, E / 2.6, fb["rho"], A, I, kappa=fb["kappa"]))
    crank, coupler, follower = links
    _clamp(mbs, crank.nodes[0], (0, 1))  # pin A: rotation of the crank free
    _clamp(mbs, follower.nodes[0], (0, 1))  # pin D
    _pin(mbs, crank.nodes[-1], coupler.nodes[0])  # B
    _pin(mbs, coupler.nodes[-1], follower.nodes[-1])  # C
    m_drive = mbs.AddMarker(eii.MarkerNodeCoordinate(nodeNumber=crank.nodes[0], coordinate=2))
    load = mbs.AddLoad(eii.LoadCoordinate(markerNumber=m_drive, load=0.0))
    drive = CreateSymbolicUserFunction(mbs, _drive_moment_symbolic, "loadUserFunction", load)
    mbs.SetLoadParameter(load, "loadUserFunction", drive)
    mbs.variables["drive"] = drive  # keep the expression tree alive during the run
    for link in links:
        link.add_sensors(mbs)
    mbs.Assemble()
    # Newton's residual (in N) stalls at ~1e-6 from round-off of the stiff links' axial forces
    # (EA/l ~ 4e9 N/m), so the default absolute tolerance 1e-10 cannot be met: case-specific values
    settings = _settings(step, until, rho_inf, rel_tol=1e-6, abs_tol=1e-5)
    setup = time.perf_counter() - t_setup
    wall = _solve_dynamic(mbs, settings)

    kinetic = potential = 0.0
    for link in links:
        times, q, v = link.histories(mbs)
        T, U = link.energies(q, v)
        kinetic, potential = kinetic + T, potential + U
        if link is crank:
            omega_A, crank_angle = v[:, 0, 2], q[:, 0, 2]
        if link is coupler:
            C = coupler.ref[None, -1, :2] + q[:, -1, :2]
    power = drive_moment(times) * omega_A
    work = np.concatenate(([0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(times))))
    balance = float(np.max(np.abs(kinetic + potential - work)) / np.max(work))
    return {
        "times": times,
        "kinetic": kinetic,
        "potential": potential,
        "input_work": work,
        "balance_error": balance,
        "wall_seconds": wall,
        "setup_seconds": setup,
        "C": C,
        "omega_A": omega_A,
        "crank_angle": crank_angle,
    }


if __name__ == "__main__":
    print(f"exudyn {exu.__version__}")
    rod = rod_free_vibration()
    span = rod["times"][-1] - rod["times"][0]
    print(
        f"rod free vibration: tip start ({rod['tip_x'][0]:.4f}, {rod['tip_y'][0]:.4f}) m, "
        f"period {rod['period']:.4f} s, energy drift {rod['energy_drift']:.2e}, "
        f"wall {rod['wall_seconds']:.3f} s ({rod['wall_seconds'] / span:.3f} s per simulated s), "
        f"setup {rod['setup_seconds']:.3f} s"
    )
    fb = four_bar()
    span = fb["times"][-1] - fb["times"][0]
    w = fb["omega_A"]
    first = w[np.nonzero(np.abs(w) > 1e-6)[0][0]]
    back = fb["times"][np.nonzero(w < 0.0)[0][0]] if first > 0 and np.any(w < 0.0) else float("nan")
    print(
        f"four-bar: balance error {fb['balance_error']:.2e}, max input work {np.max(fb['input_work']):.3f} J, "
        f"crank starts {'ccw' if first > 0 else 'cw'}, first turns back at t = {back:.3f} s, "
        f"wall {fb['wall_seconds']:.3f} s ({fb['wall_seconds'] / span:.3f} s per simulated s), "
        f"setup {fb['setup_seconds']:.3f} s"
    )
