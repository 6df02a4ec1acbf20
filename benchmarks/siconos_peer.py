"""The peer of benchmarks/impacts.py: seed 004's CSFH in Siconos (Moreau-Jean, theta = 1/2,
a 2-D friction-contact problem per step), run by Debian's own Python, which has Siconos:

    apt-get install python3-siconos
    /usr/bin/python3 benchmarks/siconos_peer.py < model.json > trace.json

It reads the model (mass, inertia, gravity, the flexure's stiffness in its end frame, the
pin and hole radii, e_N, mu, h, the end time and the start state) as JSON on stdin, and
writes the impacts, the state at given times, the final state, the seconds spent stepping
and those of the whole run (building the model, stepping, collecting the report). The pin-in-hole
contact is a linear relation y = H q + b re-linearized about the current position before
each step (a nonlinear relation of Siconos 4.4 crashed once contact became active), and the
flexure and gravity forces are set before each step at the current position: Python work
per step, which is how this peer is used. Siconos has one friction coefficient: mu.
"""

import json
import math
import sys
import time

import numpy as np
import siconos.kernel as sk


def rotation(a):
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


class Csfh:
    def __init__(self, m):
        self.m = m
        self.K = np.array(m["flexure_K"]) if m["flexure_K"] is not None else None
        self.Rf = rotation(m["flexure_frame_angle"])
        self.s = np.array(m["flexure_arm"])
        self.weight = np.array([m["mass"] * m["gravity"][0], m["mass"] * m["gravity"][1], 0.0])

    def force(self, q):
        """Gravity, and the constant-stiffness flexure: -J^T K psi, psi = [Rf^T (r + (A - 1) s); theta]."""
        f = self.weight.copy()
        if self.K is None:
            return f
        A = rotation(q[2])
        dA = np.array([[-math.sin(q[2]), -math.cos(q[2])], [math.cos(q[2]), -math.sin(q[2])]])
        psi = np.concatenate([self.Rf.T @ (q[:2] + (A - np.eye(2)) @ self.s), [q[2]]])
        J = np.zeros((3, 3))
        J[:2, :2] = self.Rf.T
        J[:2, 2] = self.Rf.T @ dA @ self.s
        J[2, 2] = 1.0
        return f - J.T @ (self.K @ psi)

    def contact(self, q):
        """(H, b) of y = H q + b: the gap (clearance - |e|) and the tangent, linearized at q."""
        e = q[:2]
        dist = max(math.hypot(e[0], e[1]), 1e-15)
        n = -e / dist  # pushes the pin back to the centre
        t = np.array([-n[1], n[0]])
        R1 = self.m["pin_radius"]
        lever = -R1 * n  # from the centre (the mass centre) to the contact point
        H = np.array([[n[0], n[1], 0.0], [t[0], t[1], lever[0] * t[1] - lever[1] * t[0]]])
        gap = self.m["hole_radius"] - R1 - dist
        b = np.array([gap - H[0] @ q, -H[1] @ q])
        return H, b


def main():
    m = json.load(sys.stdin)
    started = time.perf_counter()  # the whole run: the model built, stepped and reported
    model = Csfh(m)
    h, T = m["step"], m["until"]
    q0, v0 = np.array(m["q0"], dtype=float), np.array(m["v0"], dtype=float)
    ds = sk.LagrangianLinearTIDS(q0, v0, np.diag([m["mass"], m["mass"], m["inertia"]]))
    ds.setFExtPtr(model.force(q0))
    H, b = model.contact(q0)
    relation = sk.LagrangianLinearTIR(H, b)
    nslaw = sk.NewtonImpactFrictionNSL(m["restitution"], 0.0, m["mu"], 2)
    inter = sk.Interaction(nslaw, relation)
    nsds = sk.NonSmoothDynamicalSystem(0.0, T)
    nsds.insertDynamicalSystem(ds)
    nsds.link(inter, ds)
    osi = sk.MoreauJeanOSI(0.5)
    steps = sk.TimeStepping(nsds, sk.TimeDiscretisation(0.0, h), osi, sk.FrictionContact(2))
    wanted = sorted(m.get("at", []))
    states, impacts = {}, []
    began = time.perf_counter()
    k = 0
    while steps.hasNextEvent():
        q = np.array(ds.q())
        v_before = np.array(ds.velocity())
        ds.setFExtPtr(model.force(q + h / 2 * v_before))  # at the midpoint, as the scheme's
        H, b = model.contact(q)
        relation.setJachqPtr(H)
        relation.setEPtr(b)
        steps.computeOneStep()
        k += 1
        lam = np.array(inter.lambda_(1))
        if lam[0] > 0:
            normal_before = H[0] @ v_before
            if normal_before < 0 and (not impacts or impacts[-1]["step"] != k - 1):
                v_after = np.array(ds.velocity())
                impacts.append(
                    {
                        "time": (k - 1) * h,
                        "impulse": float(lam[0]),
                        "impact_speed": float(-normal_before),
                        "exit_speed": float(H[0] @ v_after),
                        "step": k,
                    }
                )
            elif impacts and impacts[-1]["step"] == k - 1:
                impacts[-1]["step"] = k
        steps.nextStep()
        t = k * h
        while wanted and t >= wanted[0] - 1e-12:
            states[repr(wanted.pop(0))] = list(np.array(ds.q()))
    seconds = time.perf_counter() - began
    json.dump(
        {
            "seconds": seconds,
            "total": time.perf_counter() - started,
            "steps": k,
            "impacts": impacts,
            "states": states,
            "final": list(np.array(ds.q())),
            "final_velocity": list(np.array(ds.velocity())),
        },
        sys.stdout,
    )


if __name__ == "__main__":
    main()
