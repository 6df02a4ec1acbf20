"""The peer: the same kinetostatic residual written directly in numpy, as a Matlab-style
implementation would be, for scipy.optimize.root. It reads the numbers of a compiled
Mechanism (nondimensional parameters and topology) so both sides solve the same problem."""

from __future__ import annotations

import numpy as np

from flexmech.models import Mechanism

_J = np.array([[0.0, -1.0], [1.0, 0.0]])


def _rot(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s], [s, c]])


class NumpyGripperResidual:
    """R(z) for mechanisms of curved beams with forces and moments at body reference points."""

    def __init__(self, mech: Mechanism):
        s = mech.structure
        if any(load.location != "reference" for load in s.loads):
            raise ValueError("the numpy peer handles loads at body reference points only")
        self.structure = s
        self.mechanism = mech
        self.set_parameters(mech.p())

    def set_parameters(self, p: np.ndarray) -> None:
        s, idx = self.structure, self.structure.index
        self.ref = [
            (
                np.array([p[idx[f"/bodies/{b}/position/0"]], p[idx[f"/bodies/{b}/position/1"]]]),
                p[idx[f"/bodies/{b}/angle"]],
            )
            for b in s.bodies
        ]
        self.flexures = []
        for f in s.of_family("curved_beam"):
            base = f"/elements/{f.name}"
            r, th = p[idx[f"{base}/radius"]], p[idx[f"{base}/arc_angle"]]
            a0 = p[idx[f"{base}/start_angle"]] - (th if f.reversed else 0.0)
            O = np.array([p[idx[f"{base}/center/0"]], p[idx[f"{base}/center/1"]]])
            EI = (
                p[idx[f"/materials/{f.material}/E"]]
                * p[idx[f"/sections/{f.section}/b"]]
                * p[idx[f"/sections/{f.section}/h"]] ** 3
                / 12
            )
            c, sn = np.cos(th), np.sin(th)
            C = (
                np.array(
                    [
                        [
                            r**3 / 4 * (6 * th + np.sin(2 * th) - 8 * sn),
                            r**3 / 2 * (c * c - 2 * c + 1),
                            r**2 * (th - sn),
                        ],
                        [r**3 / 2 * (c * c - 2 * c + 1), r**3 / 4 * (2 * th - np.sin(2 * th)), r**2 * (1 - c)],
                        [r**2 * (th - sn), r**2 * (1 - c), r * th],
                    ]
                )
                / EI
            )
            Ps = O + r * np.array([np.cos(a0), np.sin(a0)])
            Pe = O + r * np.array([np.cos(a0 + th), np.sin(a0 + th)])
            i, j = f.start_body, f.end_body
            s_i = _rot(self.ref[i][1]).T @ (Ps - self.ref[i][0])
            s_j = _rot(self.ref[j][1]).T @ (Pe - self.ref[j][0])
            arm0 = _rot(th).T @ np.array([r * sn, r * (1 - c)])
            self.flexures.append(
                dict(
                    i=i,
                    j=j,
                    K=np.linalg.inv(C),
                    s_i=s_i,
                    s_j=s_j,
                    p_hat=Pe - Ps,
                    b_s=a0 + np.pi / 2,
                    b_e=a0 + np.pi / 2 + th,
                    A_f=_rot(th),
                    arm0=arm0,
                    nonlinear=f.model == "partial_nonlinear",
                )
            )
        self.loads = []
        for load in s.loads:
            base = f"/loads/{load.name}"
            if load.kind == "force":
                w = np.array([p[idx[f"{base}/force/0"]], p[idx[f"{base}/force/1"]], 0.0])
            else:
                w = np.array([0.0, 0.0, p[idx[f"{base}/moment"]]])
            self.loads.append((load.body, w))
        self.free = s.free

    def __call__(self, z: np.ndarray) -> np.ndarray:
        nb = len(self.structure.bodies)
        d = np.zeros((nb, 3))
        for k, (b, c) in enumerate(self.free):
            d[b, c] = z[k]
        R = np.zeros((nb, 3))
        for f in self.flexures:
            i, j = f["i"], f["j"]
            (ri, ti), (rj, tj) = self.ref[i], self.ref[j]
            p_f = rj + d[j, :2] + _rot(tj + d[j, 2]) @ f["s_j"] - ri - d[i, :2] - _rot(ti + d[i, 2]) @ f["s_i"]
            x = _rot(-d[i, 2]) @ p_f - f["p_hat"]
            x_loc = _rot(f["b_e"]).T @ x
            psi = np.array([x_loc[0], x_loc[1], d[j, 2] - d[i, 2]])
            w = f["K"] @ psi
            arm = f["arm0"] + (x_loc if f["nonlinear"] else 0.0)
            T = -np.block([[f["A_f"], np.zeros((2, 1))], [-(arm @ _J)[None, :], np.ones((1, 1))]])
            ws = T @ w
            for b, s_loc, beta, th_hat, wr in ((j, f["s_j"], f["b_e"], tj, w), (i, f["s_i"], f["b_s"], ti, ws)):
                A = _rot(beta - th_hat)
                F_body = A @ wr[:2]
                R[b, :2] += _rot(th_hat + d[b, 2]) @ F_body
                R[b, 2] += wr[2] + s_loc[0] * F_body[1] - s_loc[1] * F_body[0]
        for b, w in self.loads:
            R[b] -= w
        return np.array([R[b, c] for b, c in self.free])
