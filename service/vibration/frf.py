"""Frequency response by modal superposition over every mode of the structure (so exact for
proportional damping), with modal damping ratios from a constant ratio and Rayleigh's terms:

    H(omega) = sum_k (C phi_k)(phi_k . f) / (omega_k^2 - omega^2 + i omega c_k),
    c_k = 2 zeta omega_k + alpha + beta omega_k^2    (D = alpha M + beta K, plus zeta on each mode)

Resonances: each elastic mode's peak of |H| per output, the local maximum nearest omega_k, with
its half-power bandwidth (|H| = peak / sqrt 2 on both sides) and quality factor f / bandwidth."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from flexmech.service.vibration.eigen import Eigen

TWO_PI = 2 * math.pi


RESONANCE_POINTS = 40  # frequencies added across each resonance in the range
FREQUENCY_BLOCK = 4096  # frequencies evaluated at once (memory: modes x block complex numbers, a few times)


@dataclass(frozen=True)
class Damping:
    ratio: float = 0.0  # zeta, on every mode
    mass: float = 0.0  # alpha (1/s)
    stiffness: float = 0.0  # beta (s)

    def rates(self, omega_k: np.ndarray) -> np.ndarray:
        """c_k = 2 zeta_k omega_k of each mode."""
        return 2 * self.ratio * omega_k + self.mass + self.stiffness * omega_k**2

    @property
    def any(self) -> bool:
        return self.ratio > 0 or self.mass > 0 or self.stiffness > 0


@dataclass
class ModalResponse:
    """The response's modal ingredients: H(omega) = P (g / (lambda - omega^2 + i omega c)) + direct,
    direct the static response of the massless directions the load pushes."""

    omega_squared: np.ndarray
    participation: np.ndarray  # P = C Phi (outputs x modes)
    forcing: np.ndarray  # g = Phi^T f (modes)
    rates: np.ndarray  # c_k
    direct: np.ndarray  # (outputs,)
    inertial: np.ndarray  # modes: Phi^T f_2, the forcing that grows with omega^2 (a prescribed motion's)
    dragged: np.ndarray  # modes: alpha Phi^T M x_qs, the forcing of alpha's drag on a carried motion, times -i omega

    def at(self, omega: np.ndarray) -> np.ndarray:
        """H (outputs x frequencies) at the circular frequencies omega (rad/s), a block of
        frequencies at a time: a modes x frequencies complex array of 400 modes and 100000
        frequencies is 0.64 GB, and the expression makes several."""
        omega = np.asarray(omega, dtype=float)
        if omega.size <= FREQUENCY_BLOCK:
            return self._at(omega)
        return np.hstack([self._at(block) for block in np.array_split(omega, -(-omega.size // FREQUENCY_BLOCK))])

    def _at(self, omega: np.ndarray) -> np.ndarray:
        denominator = self.omega_squared[:, None] - omega[None, :] ** 2 + 1j * omega[None, :] * self.rates[:, None]
        forcing = (
            self.forcing[:, None]
            + self.inertial[:, None] * omega[None, :] ** 2
            - 1j * omega[None, :] * self.dragged[:, None]
        )
        return self.participation @ (forcing / denominator) + self.direct[:, None]

    def static(self) -> np.ndarray | None:
        """H(0): None where a rigid mode is forced (no static equilibrium)."""
        if np.any(self.omega_squared <= 0):
            return None
        return self.participation @ (self.forcing / self.omega_squared) + self.direct


def modal_response(
    eigen: Eigen, C: np.ndarray, force: np.ndarray, damping: Damping, inertial=None, direct=None, carried=None
) -> ModalResponse:
    """The response to the force f (+ omega^2 `inertial` and alpha's drag on the `carried`
    momentum, a prescribed motion's), the outputs' `direct` response added."""
    values = np.where(np.array(eigen.kinds) == "rigid", 0.0, eigen.omega_squared)
    omega_k = np.sqrt(np.maximum(values, 0.0))
    inertial = np.zeros_like(force) if inertial is None else inertial
    static = np.zeros(C.shape[0]) if direct is None else np.asarray(direct, dtype=float)
    if eigen.feedthrough is not None:
        static = static + C @ (eigen.feedthrough @ force)
    carried = np.zeros_like(force) if carried is None else carried
    return ModalResponse(
        values,
        C @ eigen.shapes,
        eigen.left.T @ force,
        damping.rates(omega_k),
        static,
        eigen.left.T @ inertial,
        damping.mass * (eigen.left.T @ carried),
    )


def frequency_grid(start: float, stop: float, points: int, resonances: list[tuple[float, float]]) -> np.ndarray:
    """Hz: `points` log-spaced from start to stop, and RESONANCE_POINTS more across each resonance
    (f_k, zeta_k) in the range (+-3 bandwidths, or +-0.1 % undamped)."""
    grid = [np.geomspace(start, stop, points)]
    for f_k, zeta in resonances:
        if start < f_k < stop:
            half = 3 * zeta if zeta > 0 else 1e-3
            grid.append(
                f_k * np.linspace(max(1 - half, 0.5), 1 + half, RESONANCE_POINTS)
            )  # even: f_k itself left out (undamped, infinite)
    f = np.unique(np.concatenate(grid))
    return f[(f >= start) & (f <= stop)]


def resonances(response: ModalResponse, kinds: list[str], start: float, stop: float) -> list[dict[str, Any]]:
    """Per elastic mode in [start, stop] (Hz) and per output it moves: its peak and bandwidth.

    The peak is the local maximum of |H| nearest the mode's natural frequency within its window
    (+-4 zeta) and within its own share of the axis (nearer its frequency than any other mode's),
    solved for (bounded search) between samples of the window; the half-power points by Brent's
    roots. A neighbour's larger flank in the window does not hide it (two modes 4 % apart at
    zeta = 1 % overlap so). A mode the output moves but whose peak a neighbour drowns (no local
    maximum of its own) is given at its natural frequency, without bandwidth."""
    found = []
    shares = np.abs(response.participation * (response.forcing + response.inertial * response.omega_squared)[None, :])
    omegas = np.sqrt(np.maximum(response.omega_squared, 0.0))
    elastic = omegas[[k for k, kind in enumerate(kinds) if kind == "elastic"]]
    for k, kind in enumerate(kinds):
        omega_k = float(omegas[k])
        if kind != "elastic" or not start <= omega_k / TWO_PI <= stop or response.rates[k] <= 0:
            continue
        zeta = response.rates[k] / (2 * omega_k)
        window = omega_k * np.linspace(max(1 - 4 * zeta, 0.05), 1 + 4 * zeta, 161)
        H = np.abs(response.at(window))
        own = _own_share(window, omega_k, elastic)
        for output, row in enumerate(H):
            if shares[output, k] <= 1e-9 * shares[output].max(initial=0.0):
                continue  # the mode does not move this output

            def magnitude(omega: float, output: int = output) -> float:
                return float(abs(response.at(np.array([omega]))[output, 0]))

            top = _nearest_maximum(row, own, window, omega_k)
            if top is None:
                found.append({"mode": k + 1, "output": output, **_drowned(omega_k, response, output)})
            else:
                found.append({"mode": k + 1, "output": output, **_peak(window, row, top, magnitude, response, output)})
    return found


def _own_share(window: np.ndarray, omega_k: float, elastic: np.ndarray) -> np.ndarray:
    """Which samples of a mode's window are nearer its frequency than any other mode's
    (relatively: the midpoint on a log axis); the mode's own frequency appears once in
    `elastic`, and a mode of the same frequency shares the whole window."""
    others = elastic[np.abs(elastic - omega_k) > 1e-12 * omega_k]
    below, above = others[others < omega_k], others[others > omega_k]
    low = math.sqrt(omega_k * below.max()) if below.size else 0.0
    high = math.sqrt(omega_k * above.min()) if above.size else math.inf
    return (window > low) & (window < high)


def _nearest_maximum(row: np.ndarray, own: np.ndarray, window: np.ndarray, omega_k: float) -> int | None:
    """The index of the interior local maximum of `row` in the mode's own share nearest omega_k."""
    inner = np.arange(1, len(row) - 1)
    peaks = inner[(row[inner] >= row[inner - 1]) & (row[inner] > row[inner + 1]) & own[inner]]
    if not peaks.size:
        return None
    return int(peaks[np.argmin(np.abs(window[peaks] - omega_k))])


def _drowned(omega_k: float, response: ModalResponse, output: int) -> dict[str, Any]:
    at = complex(response.at(np.array([omega_k]))[output, 0])
    return {
        "frequency": omega_k / TWO_PI,
        "amplitude": abs(at),
        "phase": float(np.degrees(np.angle(at))),
        "bandwidth": None,
        "quality": None,
    }


def _peak(
    window: np.ndarray, row: np.ndarray, top: int, magnitude, response: ModalResponse, output: int
) -> dict[str, Any]:
    best = minimize_scalar(
        lambda omega: -magnitude(omega),
        bounds=(window[top - 1], window[top + 1]),
        method="bounded",
        options={"xatol": 1e-12 * window[top]},
    )
    omega, peak = float(best.x), -float(best.fun)
    level = peak / math.sqrt(2)
    below = np.nonzero(row[:top] < level)[0]
    above = np.nonzero(row[top:] < level)[0]
    bandwidth = None
    if below.size and above.size:
        lo, hi = below[-1], top + above[0]
        left = brentq(lambda w: magnitude(w) - level, window[lo], window[lo + 1], xtol=1e-14 * omega)
        right = brentq(lambda w: magnitude(w) - level, window[hi - 1], window[hi], xtol=1e-14 * omega)
        bandwidth = (right - left) / TWO_PI
    frequency = omega / TWO_PI
    at_peak = complex(response.at(np.array([omega]))[output, 0])
    return {
        "frequency": frequency,
        "amplitude": peak,
        "phase": float(np.degrees(np.angle(at_peak))),
        "bandwidth": bandwidth,
        "quality": frequency / bandwidth if bandwidth else None,
    }
