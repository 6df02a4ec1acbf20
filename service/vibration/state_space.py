"""The linear model of a mechanism about a state z (an equilibrium, or undeformed), for
controllers: its second-order model in the modal system's coordinates (service.vibration.modes)

    M x'' + D x' + K x + G^T lambda = F u,   G x = 0,

and a state-space model (A, B, C, D) from chosen inputs u (numeric fields, one document unit
each, as the frequency_response analysis takes them: service.vibration.harmonic) to chosen
outputs y. The states are the modal coordinates eta of the motions that carry mass (massless
ones condensed statically, as vibration_eigen does) and their rates, x = Phi eta:

    A = [[0, I], [-Lambda, -Gamma]],  B = [0; Psi^T F],  C = [Y Phi, 0],  D = Y S F + dy/du,

Lambda = diag(omega_k^2), Gamma = diag(c_k) (c_k = 2 zeta omega_k + alpha + beta omega_k^2),
Psi the left modal vectors (Phi for a symmetric K), Y the outputs' rows dy/dx, S the static
compliance the kept modes miss (the massless motions', and the modes' left out). This is
A = [[0, I], [-M^-1 K, -M^-1 D]] in the coordinates where M = I. Why modal, not a subset of x:
the Table 4.1 rod's omega spans 13 to 3.2e6 rad/s, and in a physical basis eig(A) loses 1e-7 of
its first pole to that spread; block diagonal, its poles are the modes' to round-off. Keeping
the lowest `modes` moves the static response of the rest into D (residual flexibility), so the
static gain -C A^-1 B + D stays exact.

Units: u in the fields' document units, y in the outputs', time in s; eta is mass-normalized in
the document's units (eta^2 an energy times s^2: sqrt(force*length)*s)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import null_space

from flexmech.models import Mechanism, MechanismError
from flexmech.models.graph.residual import unknown_names
from flexmech.service.vibration.eigen import Eigen, vibration_eigen
from flexmech.service.vibration.frf import Damping
from flexmech.service.vibration.harmonic import channel, moves_a_body
from flexmech.service.vibration.modes import ModalSystem, modal_system
from flexmech.service.vibration.state import check_modal_cost

MATRICES = ("A", "B", "C", "D", "M", "K", "damping", "G", "shapes")
NAMES = ("states", "inputs", "outputs", "coordinates")


@dataclass
class StateSpaceModel:
    """A, B, C, D in document units (time in s) and the second-order model behind them."""

    A: np.ndarray  # (2r, 2r): [[0, I], [-omega^2, -c]] in 1/s^2 and 1/s
    B: np.ndarray  # (2r, m): state units / s per input unit
    C: np.ndarray  # (p, 2r): output unit per state unit
    D: np.ndarray  # (p, m): output unit per input unit (massless motions, modes left out, direct)
    M: np.ndarray  # (n, n) over `coordinates`: energy s^2 / (unit_i unit_j)
    K: np.ndarray  # (n, n): energy / (unit_i unit_j)
    damping: np.ndarray  # (n, n): energy s / (unit_i unit_j), the one that gives mode k its c_k
    G: np.ndarray  # (constraints, n): G x = 0 (rows scaled as they come)
    shapes: np.ndarray  # (n, r): x = shapes eta, coordinate units per state unit
    states: list[str]
    inputs: list[str]
    outputs: list[str]
    coordinates: list[str]
    units: dict[str, Any]  # "states", "inputs", "outputs", "coordinates": lists; the matrices': text
    kinds: list[str]  # per mode: elastic, rigid or unstable

    @property
    def poles(self) -> np.ndarray:
        """(2r,) complex, rad/s: each mode's pair, from omega^2 and c in closed form."""
        r = len(self.kinds)
        values, rates = -np.diag(self.A[r:, :r]), -np.diag(self.A[r:, r:])
        root = np.sqrt((0.25 * rates**2 - values).astype(complex))
        return np.concatenate([-0.5 * rates + root, -0.5 * rates - root])

    @property
    def static_gain(self) -> np.ndarray | None:
        """-C A^-1 B + D (p, m): None with a rigid mode (no static equilibrium)."""
        r = len(self.kinds)
        values = -np.diag(self.A[r:, :r])
        if np.any(values == 0.0):
            return None
        return np.asarray(self.C[:, :r] @ (self.B[r:] / values[:, None]) + self.D)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able (numpy arrays stay arrays: service.solvers.reports.plain lists them)."""
        r = len(self.kinds)
        poles, values = self.poles, -np.diag(self.A[r:, :r])
        rates = -np.diag(self.A[r:, r:])
        omega = np.sqrt(np.abs(values))
        return {
            **{name: getattr(self, name) for name in MATRICES + NAMES},
            "units": self.units,
            "kinds": self.kinds,
            "poles": {"real": poles.real, "imag": poles.imag},
            "frequencies": [w / (2 * math.pi) if kind == "elastic" else None for w, kind in zip(omega, self.kinds)],
            "damping_ratios": [
                c / (2 * w) if kind == "elastic" else None for w, c, kind in zip(omega, rates, self.kinds)
            ],
            "static_gain": self.static_gain,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> StateSpaceModel:
        """The model of a to_dict (or of its JSON)."""
        arrays: dict[str, Any] = {name: np.asarray(data[name], dtype=float) for name in MATRICES}
        arrays["G"] = arrays["G"].reshape(-1, len(data["coordinates"]))
        arrays["shapes"] = arrays["shapes"].reshape(len(data["coordinates"]), -1)
        shapes = (
            ("A", "states", "states"),
            ("B", "states", "inputs"),
            ("C", "outputs", "states"),
            ("D", "outputs", "inputs"),
        )
        for name, rows, columns in shapes:
            arrays[name] = arrays[name].reshape(len(data[rows]), len(data[columns]))
        names: dict[str, Any] = {name: [str(n) for n in data[name]] for name in NAMES}
        return cls(**arrays, **names, units=dict(data["units"]), kinds=[str(k) for k in data["kinds"]])


def state_space_model(
    mech: Mechanism,
    z: np.ndarray | None,
    inputs: list[str] | None = None,
    outputs: list[str] | None = None,
    damping: Damping = Damping(),
    modes: int | None = None,
    pointer: str = "/state_space",
) -> StateSpaceModel:
    """The model about z (None: undeformed) from `inputs` (JSON pointers; None: every component of
    the document's loads) to `outputs` (names; None: default_outputs), the lowest `modes` kept
    (None: every one). Bad input: MechanismError at `pointer`/inputs/k, /outputs/i, /modes."""
    check_modal_cost(mech)
    z = np.zeros(mech.n_free) if z is None else np.asarray(z, dtype=float)
    inputs = default_inputs(mech, pointer) if inputs is None else list(inputs)
    outputs = default_outputs(mech) if outputs is None else list(outputs)
    if not outputs:
        raise MechanismError(f"{pointer}/outputs", "no outputs: name at least one (as in a solve's outputs)")
    system = modal_system(mech, z)
    if not np.any(system.M):  # seed 000's gripper: no mass, so the model is its static response
        if modes:
            raise MechanismError(f"{pointer}/modes", "the mechanism has no mass: it has no modes to keep")
        F, Y, direct = _channels(mech, z, system, inputs, outputs, pointer)
        return _static_model(mech, system, (F, Y, direct), (inputs, outputs))
    eigen = vibration_eigen(system.K, system.M, system.G, None)  # every mode: the truncation's rest is exact
    kept = eigen.available if modes is None else modes
    if kept > eigen.available:
        raise MechanismError(
            f"{pointer}/modes", f"{kept} modes asked, but the mechanism has {eigen.available} (its motions with mass)"
        )
    F, Y, direct = _channels(mech, z, system, inputs, outputs, pointer)
    values = np.where(np.array(eigen.kinds) == "rigid", 0.0, eigen.omega_squared)
    rates = damping.rates(np.sqrt(np.maximum(values, 0.0)))
    Phi, Psi = eigen.shapes, eigen.left
    r = kept
    A = np.block([[np.zeros((r, r)), np.eye(r)], [-np.diag(values[:r]), -np.diag(rates[:r])]])
    B = np.vstack([np.zeros((r, len(inputs))), Psi[:, :r].T @ F])
    C = np.hstack([Y @ Phi[:, :r], np.zeros((len(outputs), r))])
    D = direct + _static_rest(system, eigen, values, kept, F, Y, pointer)
    M = system.M
    second = (M, system.K, M @ Phi @ np.diag(rates) @ Psi.T @ M, _constraints(system), Phi[:, :r])
    names = ([f"mode{k + 1}" for k in range(r)] + [f"mode{k + 1}_rate" for k in range(r)], inputs, outputs)
    return _in_document_units(mech, system, (A, B, C, D), second, names, eigen.kinds[:r])


def default_inputs(mech: Mechanism, pointer: str = "/state_space") -> list[str]:
    """Every force and moment component of the document's loads (not prescribed motions)."""
    found = [
        p.pointer
        for p in mech.parameters
        if p.pointer.startswith("/loads/") and p.kind in ("force", "moment") and not moves_a_body(mech, p.pointer)
    ]
    if not found:
        raise MechanismError(
            f"{pointer}/inputs",
            "the document has no loads: name the inputs (numeric fields like /loads/<name>/force/1)",
        )
    return found


def default_outputs(mech: Mechanism) -> list[str]:
    """The positions and rotations among the document's named outputs, else every free body
    coordinate (bodies.<name>.x, .y, .angle)."""
    named = set(mech.document.outputs or {})
    g = mech.graphs
    own = [
        n for n, kind in zip(g.output_names, g.output_kinds) if n.split(".")[0] in named and kind in ("length", "angle")
    ]
    return own or [f"bodies.{name}" for name in mech.free_coordinates]


def _channels(
    mech: Mechanism, z: np.ndarray, system: ModalSystem, inputs: list[str], outputs: list[str], pointer: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(F (n, m): generalized force per unit input, Y (p, n): dy/dx, direct (p, m): dy/du), nondimensional."""
    if not inputs:
        raise MechanismError(f"{pointer}/inputs", "no inputs: name at least one (a load's component)")
    mech.parameter_indices(inputs, f"{pointer}/inputs")  # a field that is not one is named first
    forces, direct, Y = [], [], np.zeros((len(outputs), len(system.coordinates)))
    for k, path in enumerate(inputs):
        if moves_a_body(mech, path):
            raise MechanismError(
                f"{pointer}/inputs/{k}",
                f"'{path}' is a prescribed motion, which drives the model through its acceleration: "
                "name a load's component (/loads/<name>/force/1)",
            )
        try:
            link = channel(mech, z, system, path, outputs)
        except MechanismError as exc:
            where = f"{pointer}/inputs/{k}" if exc.pointer == "/input" else pointer + exc.pointer
            raise MechanismError(where, exc.problem) from None
        forces.append(link.force)
        direct.append(link.direct)
        Y = link.outputs
    return np.column_stack(forces), Y, np.column_stack(direct)


def _static_rest(
    system: ModalSystem, eigen: Eigen, values: np.ndarray, kept: int, F: np.ndarray, Y: np.ndarray, pointer: str
) -> np.ndarray:
    """(p, m) the static response the kept modes miss: the massless motions' and the left-out
    modes' (residual flexibility). Without a rigid mode, as the exact static response less the
    kept modes': the modes' own sum misses the Table 4.1 rod's tip compliance by 4.6e-9 (eigh's
    round-off over its 6e10 spread of omega^2), which D then carries, so that the static gain
    is the static solve's to round-off."""
    Phi, Psi = eigen.shapes, eigen.left
    kept_static = (
        Y @ Phi[:, :kept] @ ((Psi[:, :kept].T @ F) / np.where(values[:kept] == 0.0, 1.0, values[:kept])[:, None])
    )
    if not np.any(values == 0.0):
        Z = null_space(system.G) if system.G is not None and system.G.size else np.eye(len(system.coordinates))
        return np.asarray(Y @ Z @ np.linalg.solve(Z.T @ system.K @ Z, Z.T @ F) - kept_static)
    if np.any(values[kept:] == 0.0):
        raise MechanismError(f"{pointer}/modes", "a rigid mode cannot be left out: keep more modes")
    rest = Y @ Phi[:, kept:] @ ((Psi[:, kept:].T @ F) / values[kept:, None])
    return np.asarray(rest + (Y @ eigen.feedthrough @ F if eigen.feedthrough is not None else 0.0))


def _static_model(
    mech: Mechanism, system: ModalSystem, channels: tuple[np.ndarray, ...], names: tuple[list[str], list[str]]
) -> StateSpaceModel:
    """A massless mechanism's linear model: no states, D its static response Y K^-1 F about the
    state (within the constraints G x = 0), plus the outputs' direct dependence on the inputs."""
    F, Y, direct = channels
    inputs, outputs = names
    n = len(system.coordinates)
    Z = null_space(system.G) if system.G is not None and system.G.size else np.eye(n)
    Kr = Z.T @ system.K @ Z
    if np.linalg.svd(Kr, compute_uv=False).min(initial=1.0) <= 1e-12 * max(np.abs(Kr).max(), 1e-300):
        raise MechanismError("/bodies", "the mechanism has neither mass nor stiffness in some motion: nothing holds it")
    D = direct + Y @ Z @ np.linalg.solve(Kr, Z.T @ F)
    none = np.zeros((0, 0))
    state_space = (none, np.zeros((0, len(inputs))), np.zeros((len(outputs), 0)), D)
    second = (system.M, system.K, np.zeros_like(system.K), _constraints(system), np.zeros((n, 0)))
    return _in_document_units(mech, system, state_space, second, ([], inputs, outputs), [])


def _constraints(system: ModalSystem) -> np.ndarray:
    n = len(system.coordinates)
    return np.zeros((0, n)) if system.G is None else system.G


def _in_document_units(
    mech: Mechanism,
    system: ModalSystem,
    state_space: tuple[np.ndarray, ...],
    second: tuple[np.ndarray, ...],
    names: tuple[list[str], list[str], list[str]],
    kinds: list[str],
) -> StateSpaceModel:
    """Nondimensional (time in s) to document units: x_nd = c x_doc per coordinate, an input
    u_nd = a u_doc, an output y_nd = b y_doc, eta_nd = e eta_doc with e = sqrt(energy's)."""
    A, B, C, D = state_space
    M, K, damping, G, Phi = second
    states, inputs, outputs = names
    z_kinds = [kind for _, kind in unknown_names(mech.structure)]
    coordinate_kinds = [z_kinds[i] for i in system.x_in_state]
    c = np.array([mech.nd_per_doc(kind) for kind in coordinate_kinds])
    a = np.array([mech.nd_per_doc(mech.parameter_kind(path)) for path in inputs])
    g = mech.graphs
    output_kinds = [g.output_kinds[g.output_names.index(name)] for name in outputs]
    b = np.array([mech.nd_per_doc(kind) for kind in output_kinds])
    e = math.sqrt(mech.nd_per_doc("energy"))
    energy, per = mech.doc_unit("energy"), "/(coordinate_i*coordinate_j)"
    eta = f"sqrt({energy})*s"
    units = {
        "time": "s",
        "states": [eta] * (len(states) // 2) + [f"sqrt({energy})"] * (len(states) // 2),
        "inputs": [mech.doc_unit(mech.parameter_kind(path)) for path in inputs],
        "outputs": [mech.doc_unit(kind) for kind in output_kinds],
        "coordinates": [mech.doc_unit(kind) for kind in coordinate_kinds],
        "M": f"{energy}*s**2{per}",
        "K": f"{energy}{per}",
        "damping": f"{energy}*s{per}",
        "shapes": f"coordinate_i/({eta})",
    }
    scale = np.outer(c, c) / mech.nd_per_doc("energy")
    return StateSpaceModel(
        A,
        B * a[None, :] / e,
        C * e / b[:, None],
        D * a[None, :] / b[:, None],
        M * scale,
        K * scale,
        damping * scale,
        G * c[None, :],
        Phi * e / c[:, None],
        states,
        inputs,
        outputs,
        list(system.coordinates),
        units,
        list(kinds),
    )
