"""Assemble the equilibrium graphs of a mechanism structure (Eqs. 3-28 of seed 000, for any
number of bodies and flexures).

Residual per body b (generalized force on its coordinates x, y, angle):
    R_b = -w_b(q) + sum over flexures ending on b of N_fj K_f psi_f
                  + sum over flexures starting on b of N_if T_f K_f psi_f
Rows of free coordinates form R(z, p); rows of prescribed ones are support reactions.
The tangent stiffness K_T = dR/dz is split as in Eqs. 26-28 by differentiating through
separate copies of z: term I through psi, II through N (the body rotations carrying the
attachments), III through T'_f, and a load term through the arms of forces applied off the
reference point (zero in the paper, whose loads sit at mass centres).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca

from models import curved_beam
from models.expression import compile_expression
from models.link import LinkProperties, LinkShooting
from models.mechanism import COORDINATES, LinkTopology, Structure
from models.planar import cross, rot, unit

# Samples per shooting interval of a link, for stresses and drawing.
LINK_SAMPLES_PER_INTERVAL = 4

# Samples along each arc for the maximum bending stress and for drawing.
ARC_SAMPLES = 33


@dataclass(frozen=True)
class Graphs:
    """CasADi Functions of one structure. Inputs: z (free displacements, nondim), p (params)."""

    residual: ca.Function  # (z, p) -> R
    residual_and_tangent: ca.Function  # (z, p) -> (R, K)
    tangent_terms: ca.Function  # (z, p) -> (K_I, K_II, K_III, K_load)
    body_wrenches: ca.Function  # (d, p) -> (elastic, applied): 3 per body, d: all displacements
    displacements: ca.Function  # (z, p) -> d
    outputs: ca.Function  # (z, p) -> y
    output_names: tuple[str, ...]
    output_kinds: tuple[str, ...]
    shapes: ca.Function  # (z, p) -> (deformed, undeformed): 2 x (samples of every element)
    # per element drawn: (name, first column in shapes, columns, start body, end body)
    shape_segments: tuple[tuple[str, int, int, int, int], ...]


class _Params:
    def __init__(self, structure: Structure, p: ca.SX):
        self.index = structure.index
        self.p = p

    def __getitem__(self, pointer: str) -> ca.SX:
        return self.p[self.index[pointer]]

    def __contains__(self, pointer: str) -> bool:
        return pointer in self.index

    def vec(self, pointer: str) -> ca.SX:
        return ca.vertcat(self[f"{pointer}/0"], self[f"{pointer}/1"])


class _Builder:
    def __init__(self, structure: Structure):
        self.s = structure
        self.p = ca.SX.sym("p", len(structure.parameters))
        self.P = _Params(structure, self.p)
        self.nb = len(structure.bodies)
        self.shooting = [self._shooting(link) for link in structure.links]
        self.undeformed = [sh.undeformed_nodes() for sh in self.shooting]

    # --- links -------------------------------------------------------------------------
    def _shooting(self, link: LinkTopology) -> LinkShooting:
        return LinkShooting(self.link_properties(link), self.p, link.intervals, link.order)

    def link_properties(self, link: LinkTopology) -> LinkProperties:
        P = self.P
        base = f"/elements/{link.name}"
        E = P[f"/materials/{link.material}/E"]
        if link.shape == "curved_beam":  # the exact model of a curved beam: the arc itself
            r, theta_f = P[f"{base}/radius"], P[f"{base}/arc_angle"]
            start_angle = P[f"{base}/start_angle"] - (theta_f if link.reversed else 0)
            length = r * theta_f
            start_point = P.vec(f"{base}/center") + r * unit(start_angle)
            beta = start_angle + ca.pi / 2
            eta = lambda u: beta + theta_f * u  # noqa: E731
        else:
            length = P[f"{base}/length"]
            if link.located == "at":
                start_point = P.vec(f"{base}/at")
            else:
                start_point = self.reference(link.start_body)[0]
            eta = self._shape(link)
        I, A, fibre = self._section(link)
        EI = lambda u: E * I(u)  # noqa: E731
        EA = kGA = None
        if link.axial:
            EA = lambda u: E * A(u)  # noqa: E731
        if link.shear:
            if f"/materials/{link.material}/G" in P:
                G = P[f"/materials/{link.material}/G"]
            else:
                G = E / (2 * (1 + P[f"/materials/{link.material}/nu"]))
            kappa_pointer = f"/sections/{link.section}/shear_factor"
            kappa = P[kappa_pointer] if kappa_pointer in P else 5.0 / 6.0
            kGA = lambda u: kappa * G * A(u)  # noqa: E731
        return LinkProperties(length, eta, start_point, EI, EA, kGA, fibre)

    def _shape(self, link: LinkTopology):
        P = self.P
        base = f"/elements/{link.name}/shape"
        if link.shape == "straight":
            return lambda u: P[f"{base}/angle"] + 0 * u
        if link.shape == "arc":
            return lambda u: P[f"{base}/angle"] + P[f"{base}/sweep"] * u
        coefficients = [P[f"{base}/coefficients/{k}"] for k in range(link.terms)]
        if link.shape == "polynomial":
            return lambda u: sum((c * u**k for k, c in enumerate(coefficients)), ca.SX(0))
        if link.shape == "fourier_sine":
            return lambda u: P[f"{base}/angle"] + sum(
                (c * ca.sin((i + 1) * link.omega * u) for i, c in enumerate(coefficients)), ca.SX(0))
        build = compile_expression(link.expression, f"{base}/expression")
        return lambda u: ca.SX(build(u))

    def _section(self, link: LinkTopology):
        """I(u), A(u) and the stress factor c(u) / I(u) (None when unknown), nondimensional."""
        P = self.P
        base = f"/sections/{link.section}"
        if link.section_shape in ("rectangle", "tapered_rectangle"):
            b = P[f"{base}/b"]
            if link.section_shape == "rectangle":
                thickness = lambda u: P[f"{base}/h"] + 0 * u  # noqa: E731
            else:
                h0, h1 = P[f"{base}/h_start"], P[f"{base}/h_end"]
                thickness = lambda u: h0 + (h1 - h0) * u  # noqa: E731
            I = lambda u: b * thickness(u) ** 3 / 12  # noqa: E731
            A = lambda u: b * thickness(u)  # noqa: E731
            fibre = lambda u: 6 / (b * thickness(u) ** 2)  # noqa: E731
            return I, A, fibre
        # General: numbers are parameters; expressions are in document length units, and the
        # parameter /units/length is one document length unit (nondimensional).
        to_nd = P["/units/length"] if "/units/length" in P else 1.0

        def field(name: str, power: int, expression: str | None):
            if expression is not None:
                build = compile_expression(expression, f"{base}/{name}/expression")
                return lambda u: ca.SX(build(u)) * to_nd**power
            if f"{base}/{name}" in P:
                value = P[f"{base}/{name}"]
                return lambda u: value + 0 * u
            return None

        I = field("I", 4, link.I_expression)
        A = field("A", 2, link.A_expression)
        fibre = None
        if f"{base}/c" in P:
            c = P[f"{base}/c"]
            fibre = lambda u: c / I(u)  # noqa: E731
        return I, A, fibre

    def link_rows(self, d: list[ca.SX], z: ca.SX):
        """Per link: wrenches its bodies apply to it (start, end), its residual rows and its
        solution, for body displacements d and unknowns z."""
        out = []
        for link, shooting, undeformed, offset in zip(self.s.links, self.shooting, self.undeformed,
                                                      self.s.link_offsets):
            zl = z[offset:offset + link.unknowns]
            i, j = link.start_body, link.end_body
            (ri_hat, thi_hat), (rj_hat, thj_hat) = self.reference(i), self.reference(j)
            start0, end0 = undeformed[0][2:4], undeformed[-1][2:4]
            s_i = rot(thi_hat).T @ (start0 - ri_hat)
            s_j = rot(thj_hat).T @ (end0 - rj_hat)
            arm_i = rot(thi_hat + d[i][2]) @ s_i
            arm_j = rot(thj_hat + d[j][2]) @ s_j
            start_xy = ri_hat + d[i][:2] + arm_i
            end_xy = rj_hat + d[j][:2] + arm_j
            sol = shooting.solve_nodes(zl, start_xy, undeformed)
            end = sol.nodes[-1]
            rows = [zl[2] - d[i][2] if link.start == "clamped" else zl[3]]
            rows += sol.continuity
            rows.append(end[2:4] - end_xy)
            rows.append(end[0] - undeformed[-1][0] - d[j][2] if link.end == "clamped" else end[1])
            h, v = zl[0], zl[1]
            n = ca.vertcat(h, v)
            on_start = ca.vertcat(-n, -zl[3] + cross(arm_i, -n))
            on_end = ca.vertcat(n, end[1] + cross(arm_j, n))
            out.append((link, on_start, on_end, ca.vertcat(*rows), sol))
        return out

    # --- bodies ------------------------------------------------------------------------
    def displacements(self, z: ca.SX) -> list[ca.SX]:
        """Displacement [dx, dy, dangle] of every body, free ones from z."""
        free_index = {bc: k for k, bc in enumerate(self.s.free)}
        out = []
        for b, row in enumerate(self.s.prescribed):
            comps = []
            for c in range(3):
                if row[c] is None:
                    comps.append(z[free_index[(b, c)]])
                elif row[c] == "":
                    comps.append(ca.SX(0))
                else:
                    comps.append(self.P[row[c]])
            out.append(ca.vertcat(*comps))
        return out

    def reference(self, b: int) -> tuple[ca.SX, ca.SX]:
        name = self.s.bodies[b]
        return self.P.vec(f"/bodies/{name}/position"), self.P[f"/bodies/{name}/angle"]

    def local_point(self, b: int, base: str, location: str) -> ca.SX:
        """A point of body b in body axes, from the reference point."""
        if location == "offset":
            return self.P.vec(f"{base}/offset")
        if location == "at":
            r_hat, th_hat = self.reference(b)
            return rot(th_hat).T @ (self.P.vec(f"{base}/at") - r_hat)
        return ca.SX.zeros(2)

    def place(self, b: int, local: ca.SX, d: list[ca.SX]) -> ca.SX:
        r_hat, th_hat = self.reference(b)
        return r_hat + d[b][:2] + rot(th_hat + d[b][2]) @ local

    # --- flexures ----------------------------------------------------------------------
    def flexure(self, f, d_psi, d_N, d_T):
        """Wrenches of one curved beam on its two bodies, and its state."""
        P = self.P
        base = f"/elements/{f.name}"
        r = P[f"{base}/radius"]
        theta_f = P[f"{base}/arc_angle"]
        start_angle = P[f"{base}/start_angle"] - (theta_f if f.reversed else 0)
        E = P[f"/materials/{f.material}/E"]
        b_w, h = P[f"/sections/{f.section}/b"], P[f"/sections/{f.section}/h"]
        EI = E * b_w * h**3 / 12
        arc = curved_beam.arc_geometry(P.vec(f"{base}/center"), r, start_angle, theta_f)
        i, j = f.start_body, f.end_body
        (ri_hat, thi_hat), (rj_hat, thj_hat) = self.reference(i), self.reference(j)
        s_i = rot(thi_hat).T @ (arc.start_point - ri_hat)  # s-bar_if, body i axes
        s_j = rot(thj_hat).T @ (arc.end_point - rj_hat)  # s-bar_jf, body j axes

        def deformation(d):
            p_f = (rj_hat + d[j][:2] + rot(thj_hat + d[j][2]) @ s_j
                   - ri_hat - d[i][:2] - rot(thi_hat + d[i][2]) @ s_i)
            x_prime = rot(-d[i][2]) @ p_f - (arc.end_point - arc.start_point)  # Eq. 5
            return ca.vertcat(rot(arc.end_frame_angle).T @ x_prime, d[j][2] - d[i][2])  # Eqs. 6-8

        psi = deformation(d_psi)
        K = curved_beam.stiffness(r, theta_f, EI)
        w = K @ psi  # wrench on the beam's end, S_fj
        tip = deformation(d_T)[:2] if f.model == "partial_nonlinear" else None
        w_start = curved_beam.transfer_matrix(r, theta_f, tip) @ w  # by body i on the beam, S_if

        def on_body(b, s_local, frame_angle, th_hat, wrench):  # N of Eq. 22
            A_local = rot(frame_angle - th_hat)
            force = rot(th_hat + d_N[b][2]) @ A_local @ wrench[:2]
            moment = wrench[2] + cross(s_local, A_local @ wrench[:2])
            return ca.vertcat(force, moment)

        on_i = on_body(i, s_i, arc.start_frame_angle, thi_hat, w_start)
        on_j = on_body(j, s_j, arc.end_frame_angle, thj_hat, w)
        state = dict(psi=psi, w=w, w_start=w_start, K=K, r=r, theta_f=theta_f, b=b_w, h=h,
                     arc=arc, s_i=s_i, s_j=s_j)
        return on_i, on_j, state

    def elastic(self, d_psi, d_N, d_T):
        wrenches = [ca.SX.zeros(3) for _ in range(self.nb)]
        states = []
        for f in self.s.flexures:
            on_i, on_j, state = self.flexure(f, d_psi, d_N, d_T)
            wrenches[f.start_body] = wrenches[f.start_body] + on_i
            wrenches[f.end_body] = wrenches[f.end_body] + on_j
            states.append(state)
        return wrenches, states

    def applied(self, d):
        """External wrenches [Fx, Fy, M about the reference point] per body."""
        wrenches = [ca.SX.zeros(3) for _ in range(self.nb)]
        for load in self.s.loads:
            base = f"/loads/{load.name}"
            b = load.body
            if load.kind == "force":
                F = self.P.vec(f"{base}/force")
                arm = rot(self.reference(b)[1] + d[b][2]) @ self.local_point(b, base, load.location)
                wrenches[b] = wrenches[b] + ca.vertcat(F, cross(arm, F))
            else:
                wrenches[b] = wrenches[b] + ca.vertcat(0, 0, self.P[f"{base}/moment"])
        return wrenches

    def with_links(self, el: list[ca.SX], d: list[ca.SX], z: ca.SX):
        """Body wrenches with the links' added, and the links' own residual rows."""
        el = list(el)
        rows = []
        for link, on_start, on_end, link_rows, _ in self.link_rows(d, z):
            el[link.start_body] = el[link.start_body] + on_start
            el[link.end_body] = el[link.end_body] + on_end
            rows.append(link_rows)
        return el, rows

    def free_rows(self, per_body: list[ca.SX]) -> ca.SX:
        return ca.vertcat(*[per_body[b][c] for b, c in self.s.free]) if self.s.free else ca.SX(0, 1)

    # --- graphs ------------------------------------------------------------------------
    def build(self) -> Graphs:
        s, p = self.s, self.p
        n = s.n_unknowns
        z = ca.SX.sym("z", n)
        copies = {k: ca.SX.sym(f"z_{k}", n) for k in ("psi", "N", "T", "load")}
        d = self.displacements(z)
        dc = {k: self.displacements(v) for k, v in copies.items()}

        def residual_of(d_psi, d_N, d_T, d_load, z_links):
            # Links contribute to the first term only: their unknowns enter through psi.
            el, _ = self.elastic(d_psi, d_N, d_T)
            el, link_rows = self.with_links(el, d_psi, z_links)
            ap = self.applied(d_load)
            return ca.vertcat(self.free_rows([el[b] - ap[b] for b in range(self.nb)]), *link_rows)

        R = residual_of(d, d, d, d, z)
        K = ca.jacobian(R, z)
        R_split = residual_of(dc["psi"], dc["N"], dc["T"], dc["load"], copies["psi"])
        terms = [ca.substitute(ca.jacobian(R_split, copies[k]), ca.vertcat(*copies.values()),
                               ca.vertcat(*[z] * 4)) for k in ("psi", "N", "T", "load")]
        fn = dict(cse=True)
        residual = ca.Function("residual", [z, p], [R], ["z", "p"], ["R"], fn)
        residual_and_tangent = ca.Function("residual_and_tangent", [z, p], [R, K], ["z", "p"], ["R", "K"], fn)
        tangent_terms = ca.Function("tangent_terms", [z, p], terms, ["z", "p"],
                                    ["K_I", "K_II", "K_III", "K_load"], fn)

        d_all = ca.SX.sym("d", 3 * self.nb)
        d_split = [d_all[3 * b:3 * b + 3] for b in range(self.nb)]
        el_all, _ = self.elastic(d_split, d_split, d_split)
        ap_all = self.applied(d_split)
        body_wrenches = ca.Function("body_wrenches", [d_all, p], [ca.vertcat(*el_all), ca.vertcat(*ap_all)],
                                    ["d", "p"], ["elastic", "applied"], fn)
        displacements = ca.Function("displacements", [z, p], [ca.vertcat(*d)], ["z", "p"], ["d"], fn)

        outputs, names, kinds, shapes, segments = self._outputs(z, d)
        for f_ in (residual, residual_and_tangent, tangent_terms, body_wrenches, displacements, outputs, shapes):
            if f_.has_free():
                raise RuntimeError(f"graph {f_.name()} has free symbols {f_.get_free()}")
        return Graphs(residual, residual_and_tangent, tangent_terms, body_wrenches, displacements,
                      outputs, tuple(names), tuple(kinds), shapes, segments)

    def _outputs(self, z, d):
        s = self.s
        names: list[str] = []
        kinds: list[str] = []
        values: list[ca.SX] = []

        def emit(name, kind, value):
            names.append(name)
            kinds.append(kind)
            values.append(value)

        for b, body in enumerate(s.bodies):
            r_hat, th_hat = self.reference(b)
            emit(f"bodies.{body}.x", "length", r_hat[0] + d[b][0])
            emit(f"bodies.{body}.y", "length", r_hat[1] + d[b][1])
            emit(f"bodies.{body}.angle", "angle", th_hat + d[b][2])
        el, states = self.elastic(d, d, d)
        links = self.link_rows(d, z)
        for link, on_start, on_end, _, _ in links:
            el[link.start_body] = el[link.start_body] + on_start
            el[link.end_body] = el[link.end_body] + on_end
        ap = self.applied(d)
        for b, body in enumerate(s.bodies):
            if any(v is not None for v in s.prescribed[b]):
                # Equilibrium: applied + support - elastic = 0, so the support supplies el - ap.
                reaction = el[b] - ap[b]
                for c, q in enumerate(("Fx", "Fy", "M")):
                    emit(f"reactions.{body}.{q}", "force" if c < 2 else "moment", reaction[c])
        energy = ca.SX(0)
        for f, st in zip(s.flexures, states):
            base = f"elements.{f.name}"
            w, w_start = st["w"], st["w_start"]
            emit(f"{base}.Fx", "force", w[0])
            emit(f"{base}.Fy", "force", w[1])
            emit(f"{base}.M", "moment", w[2])
            emit(f"{base}.rotation", "angle", st["psi"][2])
            emit(f"{base}.length", "length", st["r"] * st["theta_f"])
            modulus = 6 / (st["b"] * st["h"] ** 2)  # bending stress per unit moment, rectangle
            emit(f"{base}.stress_start", "stress", modulus * ca.fabs(w_start[2]))
            emit(f"{base}.stress_end", "stress", modulus * ca.fabs(w[2]))
            moments = [ca.fabs(curved_beam.internal_moment(st["r"], st["theta_f"] * k / (ARC_SAMPLES - 1), w))
                       for k in range(ARC_SAMPLES)]
            peak = ca.fabs(w_start[2])
            for m in moments:
                peak = ca.fmax(peak, m)
            emit(f"{base}.stress_max", "stress", modulus * peak)
            e = 0.5 * ca.dot(st["psi"], st["K"] @ st["psi"])
            emit(f"{base}.energy", "energy", e)
            energy = energy + e
        link_samples = []
        for (link, _, _, _, sol), shooting in zip(links, self.shooting):
            base = f"elements.{link.name}"
            emit(f"{base}.h", "force", sol.n[0])
            emit(f"{base}.v", "force", sol.n[1])
            emit(f"{base}.M_start", "moment", sol.nodes[0][1])
            emit(f"{base}.M_end", "moment", sol.nodes[-1][1])
            emit(f"{base}.x_end", "length", sol.nodes[-1][2])
            emit(f"{base}.y_end", "length", sol.nodes[-1][3])
            emit(f"{base}.angle_start", "angle", sol.nodes[0][0])
            emit(f"{base}.angle_end", "angle", sol.nodes[-1][0])
            emit(f"{base}.rotation_start", "angle", sol.nodes[0][0] - sol.undeformed[0][0])
            emit(f"{base}.rotation_end", "angle", sol.nodes[-1][0] - sol.undeformed[-1][0])
            emit(f"{base}.length", "length", shooting.props.length)
            emit(f"{base}.x_end_undeformed", "length", sol.undeformed[-1][2])
            emit(f"{base}.y_end_undeformed", "length", sol.undeformed[-1][3])
            samples = shooting.samples(sol, LINK_SAMPLES_PER_INTERVAL)
            link_samples.append((link, samples, shooting))
            if shooting.props.fibre is not None:
                peak = ca.SX(0)
                for k, sample in enumerate(samples):
                    u = k / (len(samples) - 1)
                    peak = ca.fmax(peak, ca.fabs(sample[1]) * shooting.props.fibre(u))
                emit(f"{base}.stress_max", "stress", peak)
            emit(f"{base}.energy", "energy", sol.energy)
            emit(f"{base}.discretization_error", "dimensionless", shooting.error_estimate(sol))
            energy = energy + sol.energy
        emit("energy", "energy", energy)
        for pt in s.points:
            base = f"/outputs/{pt.name}"
            local = self.local_point(pt.body, base, pt.location)
            zero = [ca.SX.zeros(3) for _ in range(self.nb)]
            here, there = self.place(pt.body, local, d), self.place(pt.body, local, zero)
            emit(f"{pt.name}.x", "length", here[0])
            emit(f"{pt.name}.y", "length", here[1])
            emit(f"{pt.name}.dx", "length", here[0] - there[0])
            emit(f"{pt.name}.dy", "length", here[1] - there[1])
        for name, b in s.reactions:
            reaction = el[b] - ap[b]
            for c, q in enumerate(("Fx", "Fy", "M")):
                emit(f"{name}.{q}", "force" if c < 2 else "moment", reaction[c])
        outputs = ca.Function("outputs", [z, self.p], [ca.vertcat(*values)], ["z", "p"], ["y"], dict(cse=True))
        shapes, segments = self._shapes(z, d, states, link_samples)
        return outputs, names, kinds, shapes, segments

    def _shapes(self, z, d, states, link_samples):
        """Flexure centre lines for drawing: the undeformed arc, and a display of the deformed
        one that blends the two end bodies' rigid motions (exact at both ends, end tangents
        included); the beam's own deflection field is not modelled here."""
        zero = [ca.SX.zeros(3) for _ in range(self.nb)]
        deformed, undeformed = [], []
        for f, st in zip(self.s.flexures, states):
            arc = st["arc"]
            start_angle = arc.start_frame_angle - ca.pi / 2
            center = arc.start_point - st["r"] * ca.vertcat(ca.cos(start_angle), ca.sin(start_angle))
            for k in range(ARC_SAMPLES):
                t = k / (ARC_SAMPLES - 1)
                a = start_angle + t * st["theta_f"]
                pt = center + st["r"] * ca.vertcat(ca.cos(a), ca.sin(a))
                pts = []
                for b in (f.start_body, f.end_body):
                    r_hat, th_hat = self.reference(b)
                    local = rot(th_hat).T @ (pt - r_hat)
                    pts.append(self.place(b, local, d))
                blend = 3 * t**2 - 2 * t**3
                deformed.append((1 - blend) * pts[0] + blend * pts[1])
                undeformed.append(pt)
        segments = [(f.name, k * ARC_SAMPLES, ARC_SAMPLES, f.start_body, f.end_body)
                    for k, f in enumerate(self.s.flexures)]
        for link, samples, shooting in link_samples:
            segments.append((link.name, len(deformed), len(samples), link.start_body, link.end_body))
            deformed.extend(sample[2:4] for sample in samples)
            undeformed.extend(self._undeformed_samples(shooting))
        if not deformed:
            deformed = undeformed = [ca.SX.zeros(2, 0)]
        return ca.Function("shapes", [z, self.p], [ca.horzcat(*deformed), ca.horzcat(*undeformed)],
                           ["z", "p"], ["deformed", "undeformed"]), tuple(segments)

    def _undeformed_samples(self, shooting: LinkShooting) -> list[ca.SX]:
        k = self.shooting.index(shooting)
        nodes = self.undeformed[k]
        zero = ca.SX.zeros(2)
        out = []
        H = shooting.H / LINK_SAMPLES_PER_INTERVAL
        for i in range(shooting.K):
            s = nodes[i]
            out.append(s[2:4])
            for q in range(1, LINK_SAMPLES_PER_INTERVAL):
                s = shooting.step(i, s, zero, H=H, u0=i * shooting.H + (q - 1) * H)
                out.append(s[2:4])
        out.append(nodes[-1][2:4])
        return out


@lru_cache(maxsize=64)
def graphs_for(structure: Structure) -> Graphs:
    """Graphs of a structure, built once per process and reused for every parameter value."""
    return _Builder(structure).build()
