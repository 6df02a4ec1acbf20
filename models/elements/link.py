"""The link family (Lan 2005): a distributed elastica between two bodies, solved by multiple
shooting inside the graph (models.beams.link_shooting). Also the exact model of a curved beam, whose centre
line is the beam's arc.

Unknowns (4 x intervals): h, v (the internal force at u = 0, global), the start rotation and
start moment, then (psi, m, x, y) at each inner shooting node, as deviations from the
unloaded link. Rows: the start condition (clamped: rotation = the body's; pinned: m = 0), the
continuity of every inner node, the end position on the end body, and the end condition.
These unknowns mix forces and displacements, so the shooting form has no energy form (a
displacement-based discretization is the contact analysis' business).

Under gravity, a link whose material has a density carries its own weight: the internal
force falls along the link by the weight of the part behind, n(u) = n(0) - mu(u) g, with
mu(u) the mass from u = 0 (a sixth state, integrated with the others).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import casadi as ca
import numpy as np

from flexmech.models.beams.link_shooting import LinkProperties, LinkShooting, LinkSolution
from flexmech.models.documents.expression import compile_expression, finite_on
from flexmech.models.documents.sections import (
    GeneralSection,
    SectionTopology,
    nominal_EI,
    section_properties,
    section_topology,
)
from flexmech.models.elements.base import (
    CentreLine,
    Contribution,
    Discretization,
    NoEnergyForm,
    NoMassForm,
    ScaleHint,
    SiValues,
    beam_discretization,
)
from flexmech.models.elements.fibre_stress import link_stresses
from flexmech.models.elements.link_schema import Link
from flexmech.models.errors import MechanismError
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.planar import cross
from flexmech.models.graph.structure import ElementTopology

# Samples per shooting interval of a link, for stresses and drawing.
SAMPLES_PER_INTERVAL = 4
ALONG = tuple(k / 16 for k in range(17))  # where a shape expression must be a finite number


@dataclass(frozen=True)
class ShapeGeometry:
    """The centre line of a link document: its shape's eta(u), from `at` or the start body."""

    shape: str  # straight | arc | polynomial | fourier_sine | expression
    terms: int  # number of shape coefficients
    expression: str | None
    omega: float | None
    located: str  # at | reference

    def build(self, ctx: AssemblyContext, t: LinkTopology):
        """(length, start point, eta(u)) of the link, nondimensional."""
        P = ctx.P
        base = f"/elements/{t.name}"
        start_point = P.vec(f"{base}/at") if self.located == "at" else ctx.reference(t.start_body)[0]
        return P[f"{base}/length"], start_point, self._eta(P, f"{base}/shape")

    def _eta(self, P, base: str):
        if self.shape == "straight":
            return lambda u: P[f"{base}/angle"] + 0 * u
        if self.shape == "arc":
            return lambda u: P[f"{base}/angle"] + P[f"{base}/sweep"] * u
        coefficients = [P[f"{base}/coefficients/{k}"] for k in range(self.terms)]
        if self.shape == "polynomial":
            return lambda u: sum((c * u**k for k, c in enumerate(coefficients)), ca.SX(0))
        if self.shape == "fourier_sine":
            return lambda u: (
                P[f"{base}/angle"]
                + sum((c * ca.sin((i + 1) * self.omega * u) for i, c in enumerate(coefficients)), ca.SX(0))
            )
        build = compile_expression(self.expression, f"{base}/expression")
        return lambda u: ca.SX(build(u))

    def size(self, values, name: str) -> float:
        return values[f"/elements/{name}/length"]


@dataclass(frozen=True)
class LinkTopology(ElementTopology):
    start: str  # clamped | pinned
    end: str
    geometry: object  # ShapeGeometry, or a curved beam's ArcGeometry: build(ctx, t) -> (L, start, eta)
    material: str
    section: SectionTopology
    shear: bool
    axial: bool
    intervals: int
    order: int
    weighs: bool = False  # its material has a density: it has mass (and weight under gravity)

    @property
    def unknowns(self) -> int:
        """h, v, psi(0), m(0) and four states at each inner shooting node."""
        return 4 * self.intervals


@dataclass(frozen=True)
class LinkElementsTopology(LinkTopology):
    """A link discretized by elements (models.elements.link_elements contributes it)."""

    degree: int = 3

    @property
    def unknowns(self) -> int:
        """Free nodal rotations, strain coefficients, and the end conditions' multipliers."""
        rotations = self.intervals * self.degree + (1 if self.start == "pinned" else 0)
        strains = self.intervals * self.degree * (int(self.shear) + int(self.axial))
        return rotations + strains + 2 + (1 if self.end == "clamped" else 0)


def as_elements(t: LinkTopology, degree: int) -> LinkElementsTopology:
    """The same link, discretized by elements."""
    values = {f.name: getattr(t, f.name) for f in fields(t)}
    return LinkElementsTopology(**{**values, "family": "link_elements"}, degree=degree)


class LinkFamily:
    type = "link"
    schema = Link
    centre_line_sites = True  # contact sites lie on its centre line (models.contact)
    invertible = True  # the link inverse (models.beams.link_inverse) solves its shape by shooting
    fabricated = "centre_line"  # its material is its centre line grown by +-h/2 (service.drawings.fabrication)

    def discretization(self, el: Link, model: str | None) -> Discretization:
        return beam_discretization(el)

    def check_simulated(self, t: LinkTopology) -> None:
        raise MechanismError(
            f"/elements/{t.name}/discretization",
            f'link \'{t.name}\' is discretized by shooting: a simulation needs "discretization": "elements"',
        )

    def collect(self, c, name: str, el: Link, i: int, j: int) -> LinkTopology:
        base = f"/elements/{name}"
        c.use_material(el.material, f"{base}/material", shear=el.shear)
        section = c.use_section(el.section, f"{base}/section", needs_area=el.shear or el.axial)
        if el.order % 2:
            raise MechanismError(f"{base}/order", f"the integration order must be even, got {el.order}")
        c.add(f"{base}/length", el.length, "length", "positive")
        located = "reference"
        if el.at is not None:
            if c.doc.bodies[el.from_].joint:
                raise MechanismError(
                    f"{base}/at", f"a link starts at its joint's position: leave 'at' out for joint '{el.from_}'"
                )
            c.add_vec(f"{base}/at", el.at, "length")
            located = "at"
        geometry = _collect_shape(c, f"{base}/shape", el.shape, located)
        weighs = c.has_density(el.material, needs_area=True, section=el.section)
        if (el.shear or el.axial or weighs) and isinstance(section, GeneralSection) and section.A is None:
            why = (
                "shear strain"
                if el.shear
                else ("axial strain" if el.axial else f"mass (material '{el.material}' has a density)")
            )
            raise MechanismError(f"/sections/{el.section}/A", f"the area is required: link '{name}' has {why}")
        if el.start == "clamped":
            c.holds_rotation(i)
        if el.end == "clamped":
            c.holds_rotation(j)
        topology = LinkTopology(
            name,
            self.type,
            i,
            j,
            el.start,
            el.end,
            geometry,
            el.material,
            section_topology(el.section, section),
            el.shear,
            el.axial,
            el.intervals,
            el.order,
            weighs,
        )
        if el.discretization == "elements":
            return as_elements(topology, el.degree)
        return topology

    def contribute(self, ctx: AssemblyContext, t: LinkTopology, d, z) -> Contribution:
        shooting = link_shooting(ctx, t)
        attached = attach(ctx, t, shooting, d, z)
        sol = attached.solution
        samples = shooting.samples(sol, SAMPLES_PER_INTERVAL)
        outputs = [
            ("h", "force", sol.n[0]),
            ("v", "force", sol.n[1]),
            ("M_start", "moment", sol.nodes[0][1]),
            ("M_end", "moment", sol.nodes[-1][1]),
            ("x_end", "length", sol.nodes[-1][2]),
            ("y_end", "length", sol.nodes[-1][3]),
            ("angle_start", "angle", sol.nodes[0][0]),
            ("angle_end", "angle", sol.nodes[-1][0]),
            ("rotation_start", "angle", sol.nodes[0][0] - sol.undeformed[0][0]),
            ("rotation_end", "angle", sol.nodes[-1][0] - sol.undeformed[-1][0]),
            ("length", "length", shooting.props.length),
            ("x_end_undeformed", "length", sol.undeformed[-1][2]),
            ("y_end_undeformed", "length", sol.undeformed[-1][3]),
        ]
        if shooting.props.fibre is not None:
            peak = ca.SX(0)
            for k, sample in enumerate(samples):
                peak = ca.fmax(peak, ca.fabs(sample[1]) * shooting.props.fibre(k / (len(samples) - 1)))
            outputs.append(("stress_max", "stress", peak))
        outputs.append(("energy", "energy", sol.energy))
        outputs.append(("discretization_error", "dimensionless", shooting.error_estimate(sol)))
        if t.weighs:
            outputs.append(("mass", "mass", sol.undeformed[-1][5]))
        return Contribution(
            {t.start_body: attached.on_start, t.end_body: attached.on_end},
            attached.rows,
            outputs,
            sol.energy,
            _centre_line(shooting, sol, samples),
            merged=shooting.uniform,
        )

    def stress_along(self, P, t: LinkTopology, outputs: dict[str, float], points) -> np.ndarray | None:
        """The bending stress at each centre-line sample (models.elements.fibre_stress): the
        samples lie evenly in u, where stress_max takes its peak."""
        us = np.linspace(0.0, 1.0, len(points))
        return link_stresses(P, t, outputs, points, us)

    def unknowns(self, t: LinkTopology) -> list[tuple[str, str]]:
        """h, v, rotation_start, M_start, then nodeK.psi, .m, .dx, .dy of the inner nodes."""
        names = [("h", "force"), ("v", "force"), ("rotation_start", "angle"), ("M_start", "moment")]
        for k in range(1, t.intervals):
            names += [
                (f"node{k}.{q}", kind)
                for q, kind in (("psi", "angle"), ("m", "moment"), ("dx", "length"), ("dy", "length"))
            ]
        return names

    def energy_form_problem(self, t: LinkTopology) -> str | None:
        return (
            "the shooting unknowns of a link mix internal forces and displacements, so its "
            'balance is not the gradient of an energy in them; give the link "discretization": '
            '"elements" for minimum energy and contact'
        )

    def energy_terms(self, ctx, t: LinkTopology, d):
        raise NoEnergyForm(self.energy_form_problem(t))

    def kinetic_energy(self, ctx, t: LinkTopology, d, v) -> None:
        if t.weighs:
            raise NoMassForm(
                "it has mass (its material's density), but its shooting unknowns have no mass "
                "matrix: time simulation of links needs the dynamic link model"
            )
        return None

    def scale_hint(self, t: LinkTopology, values: SiValues) -> ScaleHint:
        E = values[f"/materials/{t.material}/E"]
        return ScaleHint(
            length=t.geometry.size(values, t.name), EI=nominal_EI(values, t.section, E, values.length_unit_si)
        )


def _collect_shape(c, base: str, shape, located: str) -> ShapeGeometry:
    terms, expression, omega = 0, None, None
    if shape.type in ("straight", "arc", "fourier_sine"):
        c.add(f"{base}/angle", shape.angle, "angle")
    if shape.type == "arc":
        c.add(f"{base}/sweep", shape.sweep, "angle")
    if shape.type in ("polynomial", "fourier_sine"):
        terms = len(shape.coefficients)
        for k, value in enumerate(shape.coefficients):
            c.add(f"{base}/coefficients/{k}", value, "dimensionless")
    if shape.type == "fourier_sine":
        omega = float(shape.omega)
    if shape.type == "expression":
        finite_on(compile_expression(shape.expression, f"{base}/expression"), f"{base}/expression", ALONG)
        expression = shape.expression
    return ShapeGeometry(shape.type, terms, expression, omega, located)


def exact_arc(c, name: str, el, start: int, end: int, geometry, section: SectionTopology) -> LinkTopology:
    """The exact model of a curved beam: a clamped-clamped link along its arc."""
    if el.order % 2:
        raise MechanismError(f"/elements/{name}/order", f"the integration order must be even, got {el.order}")
    topology = LinkTopology(
        name,
        "link",
        start,
        end,
        "clamped",
        "clamped",
        geometry,
        el.material,
        section,
        False,
        False,
        el.intervals,
        el.order,
        c.has_density(el.material, needs_area=False, section=el.section),
    )
    return as_elements(topology, el.degree) if el.discretization == "elements" else topology


def link_properties(ctx: AssemblyContext, t: LinkTopology) -> LinkProperties:
    P = ctx.P
    length, start_point, eta = t.geometry.build(ctx, t)
    E = P[f"/materials/{t.material}/E"]
    section = section_properties(P, t.section)
    I, A = section.I, section.A
    EI = lambda u: E * I(u)  # noqa: E731
    EA = kGA = line_mass = None
    if t.axial:
        EA = lambda u: E * A(u)  # noqa: E731
    if t.shear:
        if f"/materials/{t.material}/G" in P:
            G = P[f"/materials/{t.material}/G"]
        else:
            G = E / (2 * (1 + P[f"/materials/{t.material}/nu"]))
        kappa_pointer = f"/sections/{t.section.name}/shear_factor"
        kappa = P[kappa_pointer] if kappa_pointer in P else 5.0 / 6.0
        kGA = lambda u: kappa * G * A(u)  # noqa: E731
    gravity = None
    if t.weighs:
        rho = P[f"/materials/{t.material}/density"]
        line_mass = lambda u: length * rho * A(u)  # noqa: E731
        gravity = P.vec("/gravity") if "/gravity/0" in P else None
    return LinkProperties(
        length, eta, start_point, EI, EA, kGA, section.fibre, section.half_thickness, line_mass, gravity
    )


def link_shooting(ctx: AssemblyContext, t: LinkTopology) -> LinkShooting:
    return LinkShooting(link_properties(ctx, t), ctx.p, t.intervals, t.order)


@dataclass
class Attached:
    solution: LinkSolution
    on_start: ca.SX  # wrench the start body applies to the link
    on_end: ca.SX
    rows: ca.SX


def attach(ctx: AssemblyContext, t: LinkTopology, shooting: LinkShooting, d, zl) -> Attached:
    """The link's shooting solution with its ends on its bodies (displacements d), its rows
    and the wrenches its bodies apply to it."""
    undeformed = shooting.undeformed_nodes()
    i, j = t.start_body, t.end_body
    s_i = ctx.body_axes(i, undeformed[0][2:4])
    s_j = ctx.body_axes(j, undeformed[-1][2:4])
    arm_i, arm_j = ctx.arm(i, s_i, d), ctx.arm(j, s_j, d)
    start_xy = ctx.reference(i)[0] + d[i][:2] + arm_i
    end_xy = ctx.reference(j)[0] + d[j][:2] + arm_j
    sol = shooting.solve_nodes(zl, start_xy, undeformed)
    end = sol.nodes[-1]
    rows = [zl[2] - d[i][2] if t.start == "clamped" else zl[3]]
    rows += sol.continuity
    rows.append(end[2:4] - end_xy)
    rows.append(end[0] - undeformed[-1][0] - d[j][2] if t.end == "clamped" else end[1])
    n_start, n_end = sol.n, shooting.internal_force(sol, end)
    on_start = ca.vertcat(-n_start, -zl[3] + cross(arm_i, -n_start))
    on_end = ca.vertcat(n_end, end[1] + cross(arm_j, n_end))
    return Attached(sol, on_start, on_end, ca.vertcat(*rows))


def _centre_line(shooting: LinkShooting, sol: LinkSolution, samples: list[ca.SX]) -> CentreLine:
    undeformed = shooting.undeformed_samples(sol.undeformed, SAMPLES_PER_INTERVAL)
    half = shooting.props.half_thickness
    thickness = None
    if half is not None:
        thickness = [half(k / (len(samples) - 1)) for k in range(len(samples))]
    return CentreLine([s[2:4] for s in samples], [s[2:4] for s in undeformed], thickness)


LINK = LinkFamily()
