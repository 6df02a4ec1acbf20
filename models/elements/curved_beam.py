"""The curved-beam family (seed 000): a circular-arc flexure between two bodies.

Models: `linear` (balance of the beam in its undeformed state, Eq. 15) and
`partial_nonlinear` (in its deformed state, Eq. 17), both with the closed-form constant
stiffness of Eq. 2; `conservative`, the gradient of the energy 1/2 psi.K.psi of that
stiffness (the constant-stiffness flexure of seed 004's impact models); `exact` is the
geometrically exact elastica of the same arc, solved by shooting: that element is a link
built from the arc (models.elements.link).

Neither constant-stiffness model is the gradient of an energy: their tangent stiffness is
unsymmetric once deformed (the wrench turns with the bodies while K_f stays in the undeformed
frames), so they have no energy form. The strain energy 1/2 psi.K.psi they report is the
energy stored for the computed deformation, not a potential of the balance.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import casadi as ca
import numpy as np
from pydantic import Field

from flexmech.models.beams import curved_beam_closed_form as kernel
from flexmech.models.documents.fields import Name, Number, Vec2
from flexmech.models.documents.sections import RectangularSection, SectionTopology, nominal_EI
from flexmech.models.elements.base import (
    CentreLine,
    Contribution,
    Discretization,
    EnergyTerms,
    NoEnergyForm,
    ScaleHint,
    SiValues,
    TwoBodyElement,
    beam_discretization,
)
from flexmech.models.errors import MechanismError
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.planar import cross, rot
from flexmech.models.graph.structure import ElementTopology

MODELS = ("linear", "partial_nonlinear", "exact", "conservative")
COMPARED_MODELS = MODELS[:3]  # seed 000's three, which model comparisons draw side by side

# Samples along each arc for the maximum bending stress and for drawing.
ARC_SAMPLES = 33


class CurvedBeam(TwoBodyElement):
    """A circular-arc flexure (seed 000). The arc starts at start_angle about `center` on body
    `from` and runs by arc_angle in `direction` to body `to`."""

    type: Literal["curved_beam"]
    center: Vec2
    radius: Number
    start_angle: Number
    arc_angle: Number
    direction: Literal["ccw", "cw"] = "ccw"
    material: Name
    section: Name
    model: Literal["linear", "partial_nonlinear", "exact", "conservative"] = "partial_nonlinear"
    intervals: int = Field(default=8, ge=1, le=64, description="shooting intervals, or elements (exact model)")
    order: int = Field(default=8, ge=2, le=12, description="integration order, even (exact model by shooting)")
    discretization: Literal["shooting", "elements"] = Field(
        default="shooting",
        description="the exact model's: shooting, or elements (an energy and a mass: needed "
        "for minimum energy, contact and simulations)",
    )
    degree: int = Field(default=3, ge=1, le=6, description="exact model by elements: polynomial degree of the rotation")


@dataclass(frozen=True)
class FlexureTopology(ElementTopology):
    reversed: bool  # document gave a clockwise arc: start/end swapped for the ccw model
    model: str
    material: str
    section: str


@dataclass(frozen=True)
class ArcGeometry:
    """The centre line of a link that is a curved beam's arc (its exact model)."""

    element: str  # the curved beam's name: its fields give the arc
    reversed: bool

    def build(self, ctx: AssemblyContext, topology):
        """(length, start point, eta(u)) of the arc run counter-clockwise."""
        P = ctx.P
        base = f"/elements/{self.element}"
        r, theta_f = P[f"{base}/radius"], P[f"{base}/arc_angle"]
        start_angle = P[f"{base}/start_angle"] - (theta_f if self.reversed else 0)
        start_point = P.vec(f"{base}/center") + r * ca.vertcat(ca.cos(start_angle), ca.sin(start_angle))
        beta = start_angle + ca.pi / 2
        return r * theta_f, start_point, lambda u: beta + theta_f * u

    def size(self, values, name: str) -> float:
        return values[f"/elements/{self.element}/radius"]


class CurvedBeamFamily:
    type = "curved_beam"
    schema = CurvedBeam
    fabricated = "arc"  # its material is an annular sector (service.drawings.fabrication)

    def discretization(self, el: CurvedBeam, model: str | None) -> Discretization | None:
        """The exact model is a link inside (by shooting or by elements); the others have no
        unknowns of their own."""
        return beam_discretization(el) if (model or el.model) == "exact" else None

    # what a flexures table reports of each (elements.<name>.<output>; api.cli.report_tables)
    flexure_outputs = ("rotation", "M", "stress_start", "stress_end", "stress_max")

    def model_name(self, el: CurvedBeam) -> str:
        return el.model

    def split_contribution(self, ctx: AssemblyContext, t: FlexureTopology, d_psi, d_N, d_T) -> Contribution:
        """The flexure's wrenches with its rotation, axial and transverse parts read from separate
        copies of the displacements: Cammarata et al.'s split of K_T into terms I-III
        (models.graph.tangent_split), written for these flexures."""
        on_i, on_j, _ = flexure_wrenches(ctx, t, d_psi, d_N, d_T)
        return Contribution({t.start_body: on_i, t.end_body: on_j})

    def impact_by_statics(self, el: CurvedBeam) -> bool:
        """The exact model (a link) enters an impact simulation by its own statics stiffness
        (models.impacts.condensed); the others by the closed form below."""
        return el.model == "exact"

    def impact_flexure(self, rb, name: str, el: CurvedBeam):
        """In an impact simulation (models.impacts): (1/2 psi.K.psi, psi, K), psi seed 000's
        deformation of the arc's end relative to its start (Eqs. 5-8) in the end frame S_fj,
        exact for any rotation of the start body; every number a parameter of rb's book."""
        book, doc, base = rb.book, rb.book.document, f"/elements/{name}"
        if el.material not in doc.materials:
            raise MechanismError(f"{base}/material", f"unknown material '{el.material}'")
        if el.section not in doc.sections or not hasattr(doc.sections[el.section], "b"):
            raise MechanismError(f"{base}/section", f"'{el.section}' is not a rectangle section of the document")
        section = doc.sections[el.section]
        E = book.number(f"/materials/{el.material}/E", doc.materials[el.material].E, "stress", "positive")
        width = book.number(f"/sections/{el.section}/b", section.b, "length", "positive")
        h = book.number(f"/sections/{el.section}/h", section.h, "length", "positive")
        r = book.number(f"{base}/radius", el.radius, "length", "positive")
        theta_f = book.number(f"{base}/arc_angle", el.arc_angle, "angle", "positive")
        start_angle = book.number(f"{base}/start_angle", el.start_angle, "angle")
        centre = book.vector(f"{base}/center", el.center, "length")
        i, j = rb.body(el.from_, f"{base}/from"), rb.body(el.to, f"{base}/to")
        if el.direction == "cw":  # the model runs counter-clockwise: swap the ends
            i, j, start_angle = j, i, start_angle - theta_f
        arc = kernel.arc_geometry(centre, r, start_angle, theta_f)
        hoist = book.hoist
        start = rb.point(i, hoist(rb.body_offset(i, arc.start_point)))
        end = rb.point(j, hoist(rb.body_offset(j, arc.end_point)))
        chord, frame = hoist(arc.end_point - arc.start_point), hoist(rot(arc.end_frame_angle))
        relative = rot(-rb.rotation(i)) @ (end - start) - chord
        psi = ca.vertcat(frame.T @ relative, rb.rotation(j) - rb.rotation(i))
        K = hoist(kernel.stiffness(r, theta_f, E * width * h**3 / 12))
        return 0.5 * ca.dot(psi, K @ psi), psi, K

    def collect(self, c, name: str, el: CurvedBeam, i: int, j: int) -> ElementTopology:
        base = f"/elements/{name}"
        c.use_material(el.material, f"{base}/material")
        section = c.use_section(el.section, f"{base}/section")
        if not isinstance(section, RectangularSection):
            raise MechanismError(
                f"{base}/section", f"a curved beam needs a rectangle section ('{el.section}' is {section.shape})"
            )
        c.add_vec(f"{base}/center", el.center, "length")
        c.add(f"{base}/radius", el.radius, "length", "positive")
        c.add(f"{base}/start_angle", el.start_angle, "angle")
        c.add(f"{base}/arc_angle", el.arc_angle, "angle", "arc_angle")
        reversed_ = el.direction == "cw"
        start, end = (j, i) if reversed_ else (i, j)
        model = c.model_override or el.model
        c.holds_rotation(i)
        c.holds_rotation(j)
        if model == "exact":
            from flexmech.models.elements.link import exact_arc  # the exact model is a link

            return exact_arc(
                c, name, el, start, end, ArcGeometry(name, reversed_), SectionTopology(el.section, "rectangle")
            )
        return FlexureTopology(name, self.type, start, end, reversed_, model, el.material, el.section)

    def contribute(self, ctx: AssemblyContext, t: FlexureTopology, d, z) -> Contribution:
        if t.model == "conservative":
            on_i, on_j, state = conservative_wrenches(ctx, t, d)
        else:
            on_i, on_j, state = flexure_wrenches(ctx, t, d, d, d)
        return Contribution(
            {t.start_body: on_i, t.end_body: on_j},
            outputs=_outputs(state),
            energy=state["energy"],
            centre_line=_centre_line(ctx, t, state, d),
        )

    def unknowns(self, t: FlexureTopology) -> list[tuple[str, str]]:
        return []

    def stress_along(self, P, t: FlexureTopology, outputs: dict[str, float], points) -> np.ndarray:
        """The bending stress at each drawn sample of the arc (models.elements.fibre_stress): the
        samples stress_max takes its peak over (the segment from the section to the end balanced
        on the undeformed arc, kernel.internal_moment), and at the start section the moment the
        model balances there (stress_start: Eq. 17 with the tip displacement in the partial
        non-linear model). Their largest is stress_max, unless the undeformed balance at the
        start section exceeds every drawn sample. The drawn deformed line is a display blend of
        the bodies' motions; the stresses are the model's."""
        base, section = f"/elements/{t.name}", f"/sections/{t.section}"
        r, theta_f = P[f"{base}/radius"], P[f"{base}/arc_angle"]
        modulus = 6 / (P[f"{section}/b"] * P[f"{section}/h"] ** 2)
        w = [outputs[k] for k in ("Fx", "Fy", "M")]
        n = len(points)
        along = [abs(float(kernel.internal_moment(r, theta_f * (1 - k / (n - 1)), w))) * modulus for k in range(n)]
        along[0] = outputs["stress_start"]
        return np.array(along)

    def energy_form_problem(self, t: FlexureTopology) -> str | None:
        if t.model == "conservative":
            return None
        return (
            f"the {t.model} curved-beam model balances a constant stiffness in frames that "
            "do not turn with the bodies: its tangent stiffness is unsymmetric once deformed, "
            "so it is not the gradient of an energy (the exact model is a link)"
        )

    def energy_terms(self, ctx, t: FlexureTopology, d):
        problem = self.energy_form_problem(t)
        if problem is not None:
            raise NoEnergyForm(problem)
        return EnergyTerms(flexure_wrenches(ctx, t, d, d, d)[2]["energy"])

    def kinetic_energy(self, ctx, t: FlexureTopology, d, v) -> None:
        return None  # the constant-stiffness flexure is massless (seed 000, seed 004)

    def scale_hint(self, t: FlexureTopology, values: SiValues) -> ScaleHint:
        E = values[f"/materials/{t.material}/E"]
        section = SectionTopology(t.section, "rectangle")
        return ScaleHint(
            length=values[f"/elements/{t.name}/radius"], EI=nominal_EI(values, section, E, values.length_unit_si)
        )


def flexure_wrenches(ctx: AssemblyContext, f: FlexureTopology, d_psi, d_N, d_T):
    """Wrenches of one curved beam on its two bodies (by the bodies on the beam), and its
    state. The three displacement sets split K_T into the terms of Eqs. 26-28: psi (term I),
    the body rotations carrying the attachments, N (term II), and T'_f (term III)."""
    P = ctx.P
    base = f"/elements/{f.name}"
    r = P[f"{base}/radius"]
    theta_f = P[f"{base}/arc_angle"]
    start_angle = P[f"{base}/start_angle"] - (theta_f if f.reversed else 0)
    E = P[f"/materials/{f.material}/E"]
    b_w, h = P[f"/sections/{f.section}/b"], P[f"/sections/{f.section}/h"]
    EI = E * b_w * h**3 / 12
    arc = kernel.arc_geometry(P.vec(f"{base}/center"), r, start_angle, theta_f)
    i, j = f.start_body, f.end_body
    (ri_hat, thi_hat), (rj_hat, thj_hat) = ctx.reference(i), ctx.reference(j)
    s_i = rot(thi_hat).T @ (arc.start_point - ri_hat)  # s-bar_if, body i axes
    s_j = rot(thj_hat).T @ (arc.end_point - rj_hat)  # s-bar_jf, body j axes

    def deformation(d):
        p_f = rj_hat + d[j][:2] + rot(thj_hat + d[j][2]) @ s_j - ri_hat - d[i][:2] - rot(thi_hat + d[i][2]) @ s_i
        x_prime = rot(-d[i][2]) @ p_f - (arc.end_point - arc.start_point)  # Eq. 5
        return ca.vertcat(rot(arc.end_frame_angle).T @ x_prime, d[j][2] - d[i][2])  # Eqs. 6-8

    psi = deformation(d_psi)
    K = kernel.stiffness(r, theta_f, EI)
    w = K @ psi  # wrench on the beam's end, S_fj
    tip = deformation(d_T)[:2] if f.model == "partial_nonlinear" else None
    w_start = kernel.transfer_matrix(r, theta_f, tip) @ w  # by body i on the beam, S_if

    def on_body(b, s_local, frame_angle, th_hat, wrench):  # N of Eq. 22
        A_local = rot(frame_angle - th_hat)
        force = rot(th_hat + d_N[b][2]) @ A_local @ wrench[:2]
        moment = wrench[2] + cross(s_local, A_local @ wrench[:2])
        return ca.vertcat(force, moment)

    on_i = on_body(i, s_i, arc.start_frame_angle, thi_hat, w_start)
    on_j = on_body(j, s_j, arc.end_frame_angle, thj_hat, w)
    state = dict(
        psi=psi, w=w, w_start=w_start, r=r, theta_f=theta_f, b=b_w, h=h, arc=arc, energy=0.5 * ca.dot(psi, K @ psi)
    )
    return on_i, on_j, state


def conservative_wrenches(ctx: AssemblyContext, f: FlexureTopology, d):
    """The `conservative` model: the wrenches of the energy 1/2 psi.K.psi (psi of Eqs. 5-8, K
    of Eq. 2), exact derivatives, so its tangent stiffness is symmetric and it has an energy
    form (contact, dynamics). To first order it is the linear model."""
    i, j = f.start_body, f.end_body
    d_i, d_j = ca.SX.sym("d_i", 3), ca.SX.sym("d_j", 3)
    local = list(d)
    local[i], local[j] = d_i, d_j
    _, _, state = flexure_wrenches(ctx, f, local, local, local)
    energy = state["energy"]
    here, there = ca.vertcat(d_i, d_j), ca.vertcat(d[i], d[j])
    on_i, on_j = (ca.substitute(ca.gradient(energy, s), here, there) for s in (d_i, d_j))
    state = {k: ca.substitute(v, here, there) if isinstance(v, ca.SX) else v for k, v in state.items()}
    return on_i, on_j, state


def _outputs(st: dict) -> list[tuple[str, str, ca.SX]]:
    w, w_start = st["w"], st["w_start"]
    modulus = 6 / (st["b"] * st["h"] ** 2)  # bending stress per unit moment, rectangle
    peak = ca.fabs(w_start[2])
    for k in range(ARC_SAMPLES):
        peak = ca.fmax(peak, ca.fabs(kernel.internal_moment(st["r"], st["theta_f"] * k / (ARC_SAMPLES - 1), w)))
    return [
        ("Fx", "force", w[0]),
        ("Fy", "force", w[1]),
        ("M", "moment", w[2]),
        ("rotation", "angle", st["psi"][2]),
        ("length", "length", st["r"] * st["theta_f"]),
        ("stress_start", "stress", modulus * ca.fabs(w_start[2])),
        ("stress_end", "stress", modulus * ca.fabs(w[2])),
        ("stress_max", "stress", modulus * peak),
        ("energy", "energy", st["energy"]),
    ]


def _centre_line(ctx: AssemblyContext, f: FlexureTopology, st: dict, d) -> CentreLine:
    """The undeformed arc, and a display of the deformed one that blends the two end bodies'
    rigid motions (exact at both ends, end tangents included); the beam's own deflection
    field is not modelled by the constant-stiffness models. All samples at once, as matrices
    (2 x samples): the same operations per sample as one at a time, built several times faster."""
    arc = st["arc"]
    start_angle = arc.start_frame_angle - ca.pi / 2
    center = arc.start_point - st["r"] * ca.vertcat(ca.cos(start_angle), ca.sin(start_angle))
    ts = [k / (ARC_SAMPLES - 1) for k in range(ARC_SAMPLES)]
    a = start_angle + ca.DM(ts).T * st["theta_f"]
    points = ca.repmat(center, 1, ARC_SAMPLES) + st["r"] * ca.vertcat(ca.cos(a), ca.sin(a))
    ends = [ctx.place(b, ctx.body_axes(b, points), d) for b in (f.start_body, f.end_body)]
    blend = [3 * t**2 - 2 * t**3 for t in ts]
    deformed = ca.repmat(ca.DM([1 - q for q in blend]).T, 2, 1) * ends[0] + ca.repmat(ca.DM(blend).T, 2, 1) * ends[1]
    return CentreLine(ca.horzsplit(deformed), ca.horzsplit(points), [st["h"] / 2] * ARC_SAMPLES)


CURVED_BEAM = CurvedBeamFamily()
