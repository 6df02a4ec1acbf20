"""The element kernel of a link discretized by elements (models.beams.link_fe), in chain form: one
element's equations in terms of its own coordinates and the kinematics and force at its two
nodes, so that a link is a chain of identical kernels and every Jacobian block is local.

Coordinates of element e (n_c of them): the rotations theta at its degree + 1 nodes (the first
and last shared with its neighbours), then its shear strains gamma and axial strains eps
(degree each, when the link has them). Each enters through its value X, rate V and
acceleration A at the step's end, affine in the step's unknown u:

    X = cX + kx u,   V = cV + kv u,   A = cA + ka u

(time stepping: u the accelerations, kx = beta h^2 (1 - alpha_f) / (1 - alpha_m), ...;
statics: u = X, kv = ka = 0; consistent accelerations: kx = kv = 0, ka = 1). Each node k
carries four 2-vectors: its position r_k (as rho_k = r_k / k_rho, k_rho = kx in time steps, so
that its rows scale like the others), velocity v_k, acceleration a_k and
the force F_k that the part of the link beyond it exerts on the part before (inertia, weight
and the end body's reaction). Element e's rows:

    gen   (n_c)  generalized forces on its coordinates: the inertia and weight of its mass
                 points, the rotary inertia of its sections, its strain energy's gradient, and
                 F_{e+1} through its end (dDelta/dc^T F_{e+1})
    F_e   (2)    F_e - F_{e+1} - sum_q m_q (a_e + P''_q + alpha (v_e + P'_q) - g)
    rho   (2)    rho_{e+1} - rho_e - Delta / k_rho
    v     (2)    v_{e+1} - v_e - Delta'
    a     (2)    a_{e+1} - a_e - Delta''

with P_q the mass point q less the element's start, Delta the element's end less its start
(models.kernels.rules), ' a time derivative. Eliminating the node quantities gives back
Lagrange's equations of models.graph.dynamics exactly: the mass points' inertia summed along the
link is F, their positions summed are r.

The Jacobian is exact, written with the structure of the kinematics (every derivative of T,
T', T'' is a 2-vector lever times a basis row): three times the residual's work, where
differentiating the graph would take ten.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from flexmech.models.kernels.chain_signature import NODE, ChainSignature, split_data

ENERGIES = ("kinetic", "strain", "first_moment_x", "first_moment_y", "momentum_x", "momentum_y")


@dataclass
class _Fields:
    """An element's coordinates split into rotations, shear and axial strains."""

    theta: ca.SX
    gamma: ca.SX | None
    eps: ca.SX | None


def _split(signature: ChainSignature, c: ca.SX) -> _Fields:
    p = signature.degree
    rest = c[p + 1 :]
    gamma = rest[:p] if signature.shear else None
    eps = (rest[p : 2 * p] if signature.shear else rest[:p]) if signature.axial else None
    return _Fields(c[: p + 1], gamma, eps)


class _Tangents:
    """The tangent T, its rates T' and T'' at every point of the rule, and the 2-vectors by
    which they move with each kind of coordinate, (rotation, shear, axial) per point:

        dT/dX = dT'/dV = dT''/dA: levers  (dT/dtheta_j = levers[0] R_j, dT/dgamma_j = levers[1] S_j, ...)
        dT''/dV = 2 dT'/dX:       gyro
        dT''/dX:                   accel

    and the second derivatives of T in (psi, a = 1 + eps, b = gamma) at each point (curvature:
    d2T/dpsi2 = -L (a t + b n), d2T/dpsi da = L n, d2T/dpsi db = -L t)."""

    def __init__(self, signature: ChainSignature, X: _Fields, V: _Fields, A: _Fields, eta, L):
        pts = signature.points
        self.T, self.Td, self.Tdd, self.levers, self.gyro, self.accel, self.frame = [], [], [], [], [], [], []
        for s in range(len(pts.xi)):
            R, S = ca.DM(pts.rotation[s]), ca.DM(pts.strain[s])
            psi = eta[s] + ca.dot(R, X.theta)
            w, wd = ca.dot(R, V.theta), ca.dot(R, A.theta)
            a = 1 + (ca.dot(S, X.eps) if X.eps is not None else 0)
            ad = ca.dot(S, V.eps) if V.eps is not None else 0
            add = ca.dot(S, A.eps) if A.eps is not None else 0
            b = ca.dot(S, X.gamma) if X.gamma is not None else 0
            bd = ca.dot(S, V.gamma) if V.gamma is not None else 0
            bdd = ca.dot(S, A.gamma) if A.gamma is not None else 0
            t = ca.vertcat(ca.cos(psi), ca.sin(psi))
            n = ca.vertcat(-t[1], t[0])
            A1, B1 = ad - b * w, bd + a * w  # T' = L (A1 t + B1 n)
            A2 = add - bd * w - b * wd - B1 * w
            B2 = bdd + ad * w + a * wd + A1 * w
            self.T.append(L * (a * t + b * n))
            self.Td.append(L * (A1 * t + B1 * n))
            self.Tdd.append(L * (A2 * t + B2 * n))
            self.levers.append((L * (a * n - b * t), L * n, L * t))
            self.gyro.append((2 * L * (A1 * n - B1 * t), -2 * L * w * t, 2 * L * w * n))
            self.accel.append((L * (A2 * n - B2 * t), L * (-wd * t - w**2 * n), L * (wd * n - w**2 * t)))
            self.frame.append((a, b, t, n))


def _combine(weights: np.ndarray, vectors: list[ca.SX]) -> ca.SX:
    out = ca.SX.zeros(2)
    for weight, vector in zip(weights, vectors):
        if weight != 0.0:
            out = out + float(weight) * vector
    return out


def _lever_matrix(signature: ChainSignature, weights: np.ndarray, levers: list[tuple]) -> ca.SX:
    """(2, n_c): sum_s weights[s] dT_s/dc, for levers of the rule's points."""
    stacked = ca.horzcat(*[q for lever in levers for q in lever])
    return _weighted_levers(signature)(ca.DM(weights), stacked)


@cache
def _weighted_levers(signature: ChainSignature) -> ca.Function:
    """(weights (ns), levers (2 x 3 ns): rotation, shear, axial per point) -> (2, n_c): written
    out once per signature and called (inlined) with each sum's weights. A zero weight's term
    folds away (0 x = 0, y + 0 = y): the same expressions as writing out every sum, built once."""
    pts = signature.points
    ns = len(pts.xi)
    weights, levers = ca.SX.sym("weights", ns), ca.SX.sym("levers", 2, 3 * ns)
    blocks = [ca.SX.zeros(2, signature.degree + (k == 0)) for k in range(1 + signature.shear + signature.axial)]
    for s in range(ns):
        rotation, shear, axial = (levers[:, 3 * s + i] for i in range(3))
        bases = (
            [(rotation, pts.rotation[s])]
            + [(shear, pts.strain[s])] * signature.shear
            + [(axial, pts.strain[s])] * signature.axial
        )
        blocks = [block + weights[s] * ca.mtimes(lever, ca.DM(basis).T) for block, (lever, basis) in zip(blocks, bases)]
    return ca.Function(f"{signature.key}_weighted_levers", [weights, levers], [ca.horzcat(*blocks)])


@dataclass
class ElementSymbols:
    """The kernel's inputs."""

    u: ca.SX  # (n_local) the element's unknowns
    affine: ca.SX  # (3 n_c) cX, cV, cA of its coordinates
    k: ca.SX  # (4) kx, kv, ka, k_rho
    damping: ca.SX
    gravity: ca.SX  # (2)
    data: ca.SX  # (n_data)

    def inputs(self) -> list[ca.SX]:
        return [self.u, self.affine, self.k, self.damping, self.gravity, self.data]


INPUT_NAMES = ["u", "affine", "k", "damping", "gravity", "data"]


def element_symbols(signature: ChainSignature) -> ElementSymbols:
    return ElementSymbols(
        ca.SX.sym("u", signature.n_local),
        ca.SX.sym("affine", 3 * signature.n_c),
        ca.SX.sym("k", 4),
        ca.SX.sym("damping"),
        ca.SX.sym("gravity", 2),
        ca.SX.sym("data", signature.n_data),
    )


class ElementEquations:
    """The rows, energies and Jacobian of one element for the symbols of element_symbols()."""

    def __init__(self, signature: ChainSignature, sym: ElementSymbols):
        self.signature, self.sym = signature, sym
        sig, pts, n_c = signature, signature.points, signature.n_c
        d = split_data(sig, sym.data)
        du, L = d["du"], d["length"]
        kx, kv, ka, k_rho = sym.k[0], sym.k[1], sym.k[2], sym.k[3]
        uc = sym.u[:n_c]
        node = [sym.u[n_c + i * NODE : n_c + (i + 1) * NODE] for i in range(2)]
        rho, v, a, F = ([q[2 * j : 2 * j + 2] for q in node] for j in range(4))
        self.X = sym.affine[:n_c] + kx * uc
        self.V = sym.affine[n_c : 2 * n_c] + kv * uc
        self.A = sym.affine[2 * n_c :] + ka * uc
        X, V, A = (_split(sig, q) for q in (self.X, self.V, self.A))
        tan = _Tangents(sig, X, V, A, d["eta_points"], L)
        alpha, g = sym.damping, sym.gravity
        self.delta = du * _combine(pts.increment, tan.T)
        delta_d, delta_dd = du * _combine(pts.increment, tan.Td), du * _combine(pts.increment, tan.Tdd)
        nq = len(pts.quad_xi)
        P = [du * _combine(pts.mass_positions[q], tan.T) for q in range(nq)]
        Pd = [du * _combine(pts.mass_positions[q], tan.Td) for q in range(nq)]
        Pdd = [du * _combine(pts.mass_positions[q], tan.Tdd) for q in range(nq)]
        m, rotary = d["mass"], d["rotary"]
        f = [m[q] * (a[0] + Pdd[q] + alpha * (v[0] + Pd[q]) - g) for q in range(nq)]
        h, gen = self._mass_point_forces(tan, f, du)
        gen_theta, gen_gamma, gen_eps, self.energies = self._sections(d, X, V, A, v, k_rho * rho[0], P, Pd, gen)
        self.lever = du * _lever_matrix(sig, pts.increment, tan.levers)  # dDelta/dc (2 x n_c)
        self.gen_inner = ca.vertcat(*[q for q in (gen_theta, gen_gamma, gen_eps) if q is not None])
        self.gen = self.gen_inner + ca.mtimes(self.lever.T, F[1])
        self.force = sum(f, ca.SX.zeros(2))
        self.increments = ca.vertcat(self.delta / k_rho, delta_d, delta_dd)
        self.rows = ca.vertcat(
            self.gen,
            F[0] - F[1] - self.force,
            rho[1] - rho[0] - self.delta / k_rho,
            v[1] - v[0] - delta_d,
            a[1] - a[0] - delta_dd,
        )
        self._jacobian_parts = (
            tan,
            du,
            m,
            rotary,
            d,
            kx,
            kv,
            ka,
            alpha,
            k_rho,
            [h[s] + du * float(pts.increment[s]) * F[1] for s in range(len(pts.xi))],
        )
        self._length = L

    def _mass_point_forces(self, tan: _Tangents, f: list[ca.SX], du) -> tuple[list[ca.SX], tuple]:
        """The mass points' forces f (inertia and weight) on the coordinates: h, what acts through
        each point's tangent, and the generalized forces (theta, gamma, eps) through the levers."""
        sig, pts = self.signature, self.signature.points
        nq = len(pts.quad_xi)
        # what acts through each point's tangent: the mass points beyond it in the element (the end
        # force F_{e+1} acts through all of them: the lever dDelta/dc, self.lever)
        h = [
            du
            * sum(
                (float(pts.mass_positions[q, s]) * f[q] for q in range(nq) if pts.mass_positions[q, s]), ca.SX.zeros(2)
            )
            for s in range(len(pts.xi))
        ]
        gen_theta = ca.SX.zeros(sig.degree + 1)
        gen_gamma = ca.SX.zeros(sig.degree) if sig.shear else None
        gen_eps = ca.SX.zeros(sig.degree) if sig.axial else None
        for s in range(len(pts.xi)):
            rotation, shear, axial = tan.levers[s]
            gen_theta = gen_theta + ca.dot(h[s], rotation) * ca.DM(pts.rotation[s])
            if sig.shear:
                gen_gamma = gen_gamma + ca.dot(h[s], shear) * ca.DM(pts.strain[s])
            if sig.axial:
                gen_eps = gen_eps + ca.dot(h[s], axial) * ca.DM(pts.strain[s])
        return h, (gen_theta, gen_gamma, gen_eps)

    def _sections(self, d, X, V, A, v, r0, P, Pd, gen):
        """The sections' share at the quadrature points: rotary inertia and strain energy in the
        generalized forces gen = (theta, gamma, eps); and the element's energies
        [kinetic, strain, first moment, momentum] (the weight's potential is -g . first moment)."""
        sig, pts, alpha, du, L = self.signature, self.signature.points, self.sym.damping, d["du"], d["length"]
        gen_theta, gen_gamma, gen_eps = gen
        m, rotary, nq = d["mass"], d["rotary"], len(pts.quad_xi)
        strain, kinetic = ca.SX(0), ca.SX(0)
        momentum, first_moment = ca.SX.zeros(2), ca.SX.zeros(2)
        for q in range(nq):
            R, slope, S = ca.DM(pts.quad_rotation[q]), ca.DM(pts.quad_slope[q]), ca.DM(pts.quad_strain[q])
            weight = du * float(pts.quad_weights[q])
            # rotary inertia of the section at q
            rate, acceleration = ca.dot(R, V.theta), ca.dot(R, A.theta)
            gen_theta = gen_theta + rotary[q] * (acceleration + alpha * rate) * R
            # strain energy
            curvature = ca.dot(slope, X.theta) / du
            EI, kGA, EA = d["EI"][q], d["kGA"][q], d["EA"][q]
            gen_theta = gen_theta + weight * EI / L * curvature * slope / du
            strain = strain + weight * EI * curvature**2 / (2 * L)
            if sig.shear:
                shear_strain = ca.dot(S, X.gamma)
                gen_gamma = gen_gamma + weight * L * kGA * shear_strain * S
                strain = strain + weight * L * kGA * shear_strain**2 / 2
            if sig.axial:
                axial_strain = ca.dot(S, X.eps)
                gen_eps = gen_eps + weight * L * EA * axial_strain * S
                strain = strain + weight * L * EA * axial_strain**2 / 2
            speed = v[0] + Pd[q]
            kinetic = kinetic + m[q] * ca.dot(speed, speed) / 2 + rotary[q] * rate**2 / 2
            momentum = momentum + m[q] * speed
            first_moment = first_moment + m[q] * (r0 + P[q])
        return gen_theta, gen_gamma, gen_eps, ca.vertcat(kinetic, strain, first_moment, momentum)

    @property
    def jacobian(self) -> ca.SX:
        """(n_rows, n_local): the rows' derivative in u."""
        sig, pts, n_c = self.signature, self.signature.points, self.signature.n_c
        tan, du, m, rotary, d, kx, kv, ka, alpha, k_rho, h = self._jacobian_parts
        nq = len(pts.quad_xi)

        def levers(weights, kind):
            return du * _lever_matrix(sig, weights, kind)

        J_delta = self.lever
        J_delta_gyro, J_delta_accel = (levers(pts.increment, q) for q in (tan.gyro, tan.accel))
        # each mass point's levers, built once (the expressions are the same wherever they are used)
        P_lever, P_gyro, P_accel = (
            [levers(pts.mass_positions[q], kind) for q in range(nq)] for kind in (tan.levers, tan.gyro, tan.accel)
        )
        # d P''_q / du and d P'_q / du (P' and P'' move with X, V and A)
        dPdd = [ka * P_lever[q] + kv * P_gyro[q] + kx * P_accel[q] for q in range(nq)]
        dPd = [kv * P_lever[q] + kx / 2 * P_gyro[q] for q in range(nq)]
        df = [m[q] * (dPdd[q] + alpha * dPd[q]) for q in range(nq)]  # d f_q / du_c
        K = ca.SX.zeros(n_c, n_c)
        for q in range(nq):
            K = K + ca.mtimes(P_lever[q].T, df[q])
            rot = ca.SX.zeros(n_c, 1)
            rot[: sig.degree + 1] = ca.DM(pts.quad_rotation[q])
            K = K + rotary[q] * (ka + alpha * kv) * ca.mtimes(rot, rot.T)
        K = K + kx * (self._stiffness(d) + self._curvature(tan, h))
        eye, zero = ca.SX.eye(2), ca.SX.zeros(2, 2)
        mass_sum = sum((m[q] for q in range(nq)), ca.SX(0))
        lever_sum = sum((m[q] * P_lever[q] for q in range(nq)), ca.SX.zeros(2, n_c))
        # columns: [u_c | rho_e v_e a_e F_e | rho_{e+1} v_{e+1} a_{e+1} F_{e+1}]
        gen = ca.horzcat(K, ca.SX.zeros(n_c, 2), alpha * lever_sum.T, lever_sum.T, ca.SX.zeros(n_c, 8), J_delta.T)
        force = ca.horzcat(
            -sum(df, ca.SX.zeros(2, n_c)), zero, -alpha * mass_sum * eye, -mass_sum * eye, eye, zero, zero, zero, -eye
        )
        position = ca.horzcat(-(kx / k_rho) * J_delta, -eye, zero, zero, zero, eye, zero, zero, zero)
        velocity = ca.horzcat(-(kv * J_delta + kx / 2 * J_delta_gyro), zero, -eye, zero, zero, zero, eye, zero, zero)
        acceleration = ca.horzcat(
            -(ka * J_delta + kv * J_delta_gyro + kx * J_delta_accel), zero, zero, -eye, zero, zero, zero, eye, zero
        )
        return ca.vertcat(gen, force, position, velocity, acceleration)

    def _curvature(self, tan: _Tangents, h: list[ca.SX]) -> ca.SX:
        """sum_s (d2 T_s / dc2) . h_s: how the levers turn with the coordinates, against what acts
        through each point (the geometric stiffness)."""
        sig, pts = self.signature, self.signature.points
        p, n_c = sig.degree, sig.n_c
        K = ca.SX.zeros(n_c, n_c)
        for s in range(len(pts.xi)):
            a, b, t, n = tan.frame[s]
            L = self._length
            hs = h[s]
            # the point's (psi, a, b) from the coordinates: B (3 x n_c)
            B = ca.SX.zeros(3, n_c)
            B[0, : p + 1] = ca.DM(pts.rotation[s]).T
            k = p + 1
            rows = {}
            if sig.shear:
                rows["b"] = k
                k += p
            if sig.axial:
                rows["a"] = k
            if "a" in rows:
                B[1, rows["a"] : rows["a"] + p] = ca.DM(pts.strain[s]).T
            if "b" in rows:
                B[2, rows["b"] : rows["b"] + p] = ca.DM(pts.strain[s]).T
            H = ca.SX.zeros(3, 3)
            H[0, 0] = -L * ca.dot(hs, a * t + b * n)
            H[0, 1] = H[1, 0] = L * ca.dot(hs, n)
            H[0, 2] = H[2, 0] = -L * ca.dot(hs, t)
            K = K + ca.mtimes(B.T, ca.mtimes(H, B))
        return K

    def _stiffness(self, d) -> ca.SX:
        """The strain energy's Hessian in the coordinates (constant)."""
        sig, pts = self.signature, self.signature.points
        p, n_c, du, L = sig.degree, sig.n_c, d["du"], d["length"]
        K = ca.SX.zeros(n_c, n_c)
        for q in range(len(pts.quad_xi)):
            weight = du * float(pts.quad_weights[q])
            slope = ca.DM(pts.quad_slope[q]) / du
            K[: p + 1, : p + 1] = K[: p + 1, : p + 1] + weight * d["EI"][q] / L * ca.mtimes(slope, slope.T)
            S = ca.DM(pts.quad_strain[q])
            k = p + 1
            for present, stiffness in ((sig.shear, d["kGA"][q]), (sig.axial, d["EA"][q])):
                if present:
                    K[k : k + p, k : k + p] = K[k : k + p, k : k + p] + weight * L * stiffness * ca.mtimes(S, S.T)
                    k += p
        return K


def residual_function(signature: ChainSignature) -> ca.Function:
    """(u, affine, k, damping, gravity, data) -> (rows, energies)."""
    sym = element_symbols(signature)
    eq = ElementEquations(signature, sym)
    return ca.Function(
        f"{signature.key}_residual",
        sym.inputs(),
        [eq.rows, eq.energies],
        INPUT_NAMES,
        ["rows", "energies"],
        {"cse": True},
    )


def jacobian_function(signature: ChainSignature) -> ca.Function:
    """(u, affine, k, damping, gravity, data) -> (rows, J)."""
    sym = element_symbols(signature)
    eq = ElementEquations(signature, sym)
    return ca.Function(
        f"{signature.key}_jacobian", sym.inputs(), [eq.rows, eq.jacobian], INPUT_NAMES, ["rows", "J"], {"cse": True}
    )
