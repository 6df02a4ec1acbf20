"""Peer: the gripping-contact method of Lan (2005), Chapter 6, Example I, with scipy's SLSQP.

Method (as in the thesis, no shear):
- Eqs. 6.11-6.15: the finger is split into N equal intervals of length h = L/N; the unknowns
  are the nodal angles psi_1..psi_N (psi_0 = 0, x(0) = y(0) = 0, Eq. 6.14); the neutral
  axis follows by the trapezoidal rule (Eq. 6.15) and the strain energy is
  V = sum_i EI_{i+1/2} / (2 h) (psi_{i+1} - psi_i)^2 (Eq. 6.12, EI at mid-intervals, 6.13).
- Eqs. 6.16 and 6.20: M equally spaced points of the jaw's lead face ab (both ends
  included) must stay outside the fixture circle, (X_j - x_o)^2 + (Y_j - y_o)^2 - R^2 >= 0.
- The problem is solved by an SQP method with a BFGS Hessian (Sec. 6.3): here
  scipy.optimize.minimize(method="SLSQP") with exact, vectorized gradients.
- Contact force (Sec. 6.2.3), frictionless: the clamp moment from a forward difference,
  M0 = EI (psi_1 - psi_0) / h, equals P_C x F (Eq. 6.6, F on the finger), and F is parallel
  to the circle's gradient at the contact point P_C (Eq. 6.8). The force from the SLSQP
  multipliers, F = sum_j lambda_j grad g_j, is returned as well when scipy exposes them.

Geometry (reading notes, seed 002): straight finger E = 2.6 GPa, in-plane thickness
w = 3.2 mm, width b = 9.5 mm, L = 57 mm, clamped at the origin along +x. Rigid triangular
jaw in the tip-section frame (origin at the end of the neutral axis, x along the tip
tangent): nose a = (19, 1.6) mm, crest b = (0, 10.4598) mm; the jaw turns with the tip,
R(+psi_N) (the minus sign of Eq. 6.4 is a typo). Fixture circle R = 8.9 mm, centre
(x_o, 10.5 mm). Forces returned are forces ON THE FINGER (the thesis' F is on the object).
Units: SI (m, N, N m).
"""

from __future__ import annotations

import time

import numpy as np
from scipy.optimize import minimize

E_MODULUS = 2.6e9  # Pa
THICKNESS = 3.2e-3  # m, in-plane (bending) thickness w
WIDTH = 9.5e-3  # m, out-of-plane width b
LENGTH = 57e-3  # m
JAW_NOSE = np.array([19e-3, 1.6e-3])  # a, tip-section frame
JAW_CREST = np.array([0.0, 10.4598e-3])  # b, tip-section frame
FIXTURE_RADIUS = 8.9e-3  # m
FIXTURE_Y = 10.5e-3  # m
BENDING_STIFFNESS = E_MODULUS * WIDTH * THICKNESS**3 / 12.0


class ExampleOneProblem:
    """Discrete Example I (Eqs. 6.12-6.16, 6.20) for unknowns z = (psi_1..psi_N).

    The constraints are divided by R^2 (a positive constant: same feasible set, better
    conditioned QP); multipliers are converted back when forces are computed.
    """

    def __init__(self, x_o: float, N: int, M: int):
        self.N, self.h = N, LENGTH / N
        self.centre = np.array([x_o, FIXTURE_Y])
        self.scale = 1.0 / FIXTURE_RADIUS**2
        self.ei_mid = np.full(N, BENDING_STIFFNESS)  # EI_{i+1/2}, uniform finger
        self.weights = np.ones(N + 1)  # trapezoidal weights (Eq. 6.15)
        self.weights[[0, -1]] = 0.5
        t = np.linspace(0.0, 1.0, M)[:, None]
        self.face = JAW_NOSE + t * (JAW_CREST - JAW_NOSE)  # M points of face ab, jaw frame

    def full(self, z: np.ndarray) -> np.ndarray:
        """Nodal angles psi_0..psi_N with the clamp condition psi_0 = 0 (Eq. 6.14)."""
        return np.concatenate(([0.0], z))

    def energy(self, z: np.ndarray) -> float:
        """Strain energy, Eq. 6.12 without shear."""
        d = np.diff(self.full(z))
        return float(np.sum(self.ei_mid * d * d) / (2.0 * self.h))

    def energy_gradient(self, z: np.ndarray) -> np.ndarray:
        """dV/dpsi_k = c_{k-1} - c_k with c_i = EI_{i+1/2} (psi_{i+1} - psi_i) / h, c_N = 0."""
        c = self.ei_mid * np.diff(self.full(z)) / self.h
        return c - np.append(c[1:], 0.0)

    def face_points(self, z: np.ndarray):
        """Tip (Eq. 6.15), tip angle and the face points in the finger frame (Eq. 6.4)."""
        psi = self.full(z)
        wc, ws = self.weights * np.cos(psi), self.weights * np.sin(psi)
        tip = self.h * np.array([wc.sum(), ws.sum()])
        c, s = np.cos(psi[-1]), np.sin(psi[-1])
        rotated = self.face @ np.array([[c, s], [-s, c]])  # rows R(+psi_N) p
        return tip, rotated, tip + rotated, (wc, ws)

    def constraints(self, z: np.ndarray) -> np.ndarray:
        """Scaled Eq. 6.20: ((X_j - x_o)^2 + (Y_j - y_o)^2 - R^2) / R^2 >= 0."""
        _, _, pts, _ = self.face_points(z)
        d = pts - self.centre
        return self.scale * (np.einsum("ij,ij->i", d, d) - FIXTURE_RADIUS**2)

    def constraints_jacobian(self, z: np.ndarray) -> np.ndarray:
        """d g_j / d psi_k (M x N): tip translation for all k, jaw rotation for k = N."""
        _, rotated, pts, (wc, ws) = self.face_points(z)
        d = 2.0 * self.scale * (pts - self.centre)  # grad of scaled g at each point
        dtip_x, dtip_y = -self.h * ws[1:], self.h * wc[1:]  # dX_N/dpsi_k, dY_N/dpsi_k
        jac = np.outer(d[:, 0], dtip_x) + np.outer(d[:, 1], dtip_y)
        jac[:, -1] += d[:, 1] * rotated[:, 0] - d[:, 0] * rotated[:, 1]  # d(R p)/dpsi_N = J R p
        return jac


def recover_force(problem: ExampleOneProblem, z: np.ndarray, contact: int):
    """Frictionless force on the finger from the clamp moment (Eqs. 6.6 and 6.8).

    M0 = EI (psi_1 - psi_0)/h is the moment the finger section at s = 0 carries, equal to
    P_C x F_finger (= -P_C x F_object, Eq. 6.6); F_finger = f n with n = grad g(P_C).
    """
    _, _, pts, _ = problem.face_points(z)
    moment = problem.ei_mid[0] * z[0] / problem.h
    p_c = pts[contact]
    normal = p_c - problem.centre  # parallel to grad g, Eq. 6.8
    normal /= np.linalg.norm(normal)
    f = moment / (p_c[0] * normal[1] - p_c[1] * normal[0])
    return f * normal, moment, p_c


def _start_vector(psi_start: np.ndarray | None, N: int) -> np.ndarray:
    """psi_1..psi_N from a warm start of length N + 1 (psi_0..psi_N) or N, or zeros."""
    if psi_start is None:
        return np.zeros(N)
    psi_start = np.asarray(psi_start, dtype=float)
    if psi_start.size == N + 1:
        return psi_start[1:].copy()
    if psi_start.size == N:
        return psi_start.copy()
    raise ValueError(f"psi_start has {psi_start.size} entries, expected {N + 1} or {N}")


def example_one_state(x_o_mm: float, N: int = 400, M: int = 100, psi_start: np.ndarray | None = None) -> dict:
    """Solve one frictionless contact state of Example I with the fixture centre at x_o_mm.

    Returns the contact force on the finger recovered by Eqs. 6.6/6.8 ("force_x",
    "force_y", N), the clamp moment (N m), the contact point (m, finger frame), the wall
    time of the minimize call ("seconds"), "iterations", "success", "message", the nodal
    angles psi_0..psi_N ("psi", usable as psi_start) and, when scipy exposes the SLSQP
    multipliers, the force from them ("multiplier_force_x", "multiplier_force_y").
    """
    problem = ExampleOneProblem(x_o_mm * 1e-3, N, M)
    z0 = _start_vector(psi_start, N)
    cons = [{"type": "ineq", "fun": problem.constraints, "jac": problem.constraints_jacobian}]
    t0 = time.perf_counter()
    res = minimize(
        problem.energy,
        z0,
        jac=problem.energy_gradient,
        method="SLSQP",
        constraints=cons,
        options={"maxiter": 500, "ftol": 1e-12},
    )
    seconds = time.perf_counter() - t0
    z = res.x
    lam = getattr(res, "multipliers", None)
    lam = None if lam is None else np.asarray(lam, dtype=float).ravel()
    contact = int(np.argmax(lam)) if lam is not None and lam.size == M else int(np.argmin(problem.constraints(z)))
    force, moment, p_c = recover_force(problem, z, contact)
    out = {
        "force_x": float(force[0]),
        "force_y": float(force[1]),
        "clamp_moment": float(moment),
        "contact_point": (float(p_c[0]), float(p_c[1])),
        "seconds": seconds,
        "iterations": int(res.nit),
        "success": bool(res.success),
        "message": str(res.message),
        "psi": problem.full(z),
    }
    if lam is not None and lam.size == M:
        _, _, pts, _ = problem.face_points(z)
        f_mult = (lam * 2.0 * problem.scale)[:, None] * (pts - problem.centre)
        out["multiplier_force_x"], out["multiplier_force_y"] = map(float, f_mult.sum(axis=0))
    return out


def main() -> None:
    """Example I at x_o = 67.81 mm (the state of the thesis' Fig. 6.5) at two resolutions."""
    for N, M in ((100, 100), (400, 100)):
        r = example_one_state(67.81, N=N, M=M)
        line = (
            f"N={N:4d} M={M:4d}  force_x={r['force_x']:+.5f} N  force_y={r['force_y']:+.5f} N"
            f"  seconds={r['seconds']:.4f}  iterations={r['iterations']}"
        )
        if "multiplier_force_x" in r:
            line += f"  (multipliers: {r['multiplier_force_x']:+.5f}, {r['multiplier_force_y']:+.5f} N)"
        print(line)
        print(
            f"    contact point = ({r['contact_point'][0] * 1e3:.3f}, {r['contact_point'][1] * 1e3:.3f}) mm"
            f"  clamp moment = {r['clamp_moment']:+.5f} N m  success={r['success']} ({r['message']})"
        )


if __name__ == "__main__":
    main()
