"""Links with the displacement-based discretization (models.beams.link_fe): a link document with
`discretization: "elements"`. Its model is an energy, so it has an energy form (minimum
energy, contact) as well as a residual form (the stationarity of that energy).

Unknowns: the nodal rotations theta_k (deviations from the unloaded link; theta_0 only when
the start is pinned: clamped, it is the start body's rotation), the shear and axial strain
coefficients when the link has them, then the multipliers of the end conditions: the end
position on the end body (two) and, clamped, the end rotation (one).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from flexmech.models.beams.link_fe import LinkElements, LinkKinematics, element_rule
from flexmech.models.documents.sections import section_properties
from flexmech.models.elements.base import (
    CentreLine,
    Contribution,
    EnergyTerms,
    InertiaPoint,
    NoMassForm,
    ScaleHint,
    SiValues,
)
from flexmech.models.elements.fibre_stress import link_stresses
from flexmech.models.elements.link import LINK, LinkElementsTopology, link_properties
from flexmech.models.elements.link_schema import Link
from flexmech.models.elements.surfaces import ElementSurfaces, SurfacePoint
from flexmech.models.elements.variational import variational_parts
from flexmech.models.errors import MechanismError
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.planar import cross


@dataclass
class _Stated:
    terms: EnergyTerms
    kinematics: LinkKinematics
    undeformed: LinkKinematics
    arms: tuple[ca.SX, ca.SX]  # from the start and end bodies' reference points to the link's ends


class LinkElementsFamily:
    type = "link_elements"
    schema = None  # a `link` document with discretization "elements"
    centre_line_sites = True  # contact sites lie on its centre line (models.contact)
    kernel_chain = True  # it runs as a chain of element kernels (models.kernels)

    def energy_form_counts(self, t: LinkElementsTopology) -> tuple[int, int]:
        """(own variables, equalities) in the energy form: its rotations and strains; the end
        conditions."""
        rotations = t.intervals * t.degree + (1 if t.start == "pinned" else 0)
        strains = t.intervals * t.degree * (int(t.shear) + int(t.axial))
        return rotations + strains, 2 + (1 if t.end == "clamped" else 0)

    def check_simulated(self, t: LinkElementsTopology) -> None:
        if not t.weighs:
            raise MechanismError(
                f"/materials/{t.material}/density",
                f"link '{t.name}' has no mass: give its material '{t.material}' a density",
            )

    def collect(self, c, name: str, el: Link, i: int, j: int) -> LinkElementsTopology:
        raise RuntimeError("links by elements are collected by the link family")

    def _state(self, ctx: AssemblyContext, t: LinkElementsTopology, d: list[ca.SX]) -> _Stated:
        props = link_properties(ctx, t)
        disc = LinkElements(props, t.intervals, t.degree)
        i, j = t.start_body, t.end_body
        n_free_rotations = disc.n_rotations - (1 if t.start == "clamped" else 0)
        parts = [ca.SX.sym(f"{t.name}_theta", n_free_rotations)]
        theta = ca.vertcat(d[i][2], parts[0]) if t.start == "clamped" else parts[0]
        strains = {}
        for field_name, present in (("gamma", t.shear), ("eps", t.axial)):
            if present:
                strains[field_name] = ca.SX.sym(f"{t.name}_{field_name}", disc.n_strains)
                parts.append(strains[field_name])
        undeformed = disc.kinematics(ca.SX.zeros(disc.n_rotations), None, None, props.start_point)
        arm_i = ctx.arm(i, ctx.body_axes(i, props.start_point), d)
        arm_j = ctx.arm(j, ctx.body_axes(j, undeformed.node_position[-1]), d)
        start = ctx.reference(i)[0] + d[i][:2] + arm_i
        weighs = props.line_mass is not None and props.gravity is not None
        kin = disc.kinematics(
            theta, strains.get("gamma"), strains.get("eps"), start, positions_at_quadrature=props.line_mass is not None
        )
        end_target = ctx.reference(j)[0] + d[j][:2] + arm_j
        equalities = [
            ("end.x", kin.node_position[-1][0] - end_target[0]),
            ("end.y", kin.node_position[-1][1] - end_target[1]),
        ]
        if t.end == "clamped":
            equalities.append(("end.rotation", kin.node_psi[-1] - undeformed.node_psi[-1] - d[j][2]))
        energy = kin.strain_energy
        if weighs:  # the link's own weight
            for point in kin.points:
                energy = energy - point.weight * props.line_mass(ca.SX(point.u)) * ca.dot(props.gravity, point.position)
        half = props.half_thickness
        surface = [SurfacePoint(0.0, start, _normal(kin.node_psi[0]), half(ca.SX(0.0)) if half else None)]
        surface += [
            SurfacePoint(q.u, q.position, q.normal, half(ca.SX(q.u)) if half else None, q.weight)
            for q in kin.contact_points
        ]
        surface.append(
            SurfacePoint(1.0, kin.node_position[-1], _normal(kin.node_psi[-1]), half(ca.SX(1.0)) if half else None)
        )
        surfaces = ElementSurfaces(
            {"start": (start, kin.node_psi[0]), "end": (kin.node_position[-1], kin.node_psi[-1])}, surface
        )
        inertia = []
        if props.line_mass is not None:  # its mass and the rotary inertia of its sections (rho I)
            density, second_moment = _density_and_I(ctx, t)
            inertia = [
                InertiaPoint(
                    q.position,
                    q.weight * props.line_mass(ca.SX(q.u)),
                    q.psi,
                    q.weight * props.length * density * second_moment(ca.SX(q.u)),
                )
                for q in kin.points
            ]
        terms = EnergyTerms(energy, equalities, [], ca.vertcat(*parts), surfaces, inertia)
        return _Stated(terms, kin, undeformed, (arm_i, arm_j))

    def energy_terms(self, ctx: AssemblyContext, t: LinkElementsTopology, d: list[ca.SX]) -> EnergyTerms:
        return self._state(ctx, t, d).terms

    def contribute(self, ctx: AssemblyContext, t: LinkElementsTopology, d, z) -> Contribution:
        i, j = t.start_body, t.end_body
        stated = {}

        def build(local):
            stated["s"] = s = self._state(ctx, t, local)
            kin = s.kinematics
            extras = [
                kin.node_position[-1],
                kin.node_psi[0],
                kin.node_psi[-1],
                *kin.node_position,
                *[q.position for q in kin.contact_points],
                kin.elongation,
                *s.arms,
            ]
            return s.terms, extras

        wrenches, rows, energy, extras = variational_parts((i, j), ctx.n_bodies, d, z, build)
        s = stated["s"]
        n_nodes, n_points = len(s.kinematics.node_position), len(s.kinematics.contact_points)
        end, psi_start, psi_end = extras[0], extras[1], extras[2]
        nodes = extras[3 : 3 + n_nodes]
        points = extras[3 + n_nodes : 3 + n_nodes + n_points]
        elongation, arm_i, arm_j = extras[-3:]
        on_start, on_end = wrenches[i], wrenches[j]
        n_start = -on_start[:2]  # the internal force at u = 0 (what the part beyond exerts on the start)
        m_start = -(on_start[2] - cross(arm_i, on_start[:2]))
        m_end = on_end[2] - cross(arm_j, on_end[:2])
        und = s.undeformed
        outputs = [
            ("h", "force", n_start[0]),
            ("v", "force", n_start[1]),
            ("M_start", "moment", m_start),
            ("M_end", "moment", m_end),
            ("x_end", "length", end[0]),
            ("y_end", "length", end[1]),
            ("x_start", "length", nodes[0][0]),
            ("y_start", "length", nodes[0][1]),
            ("angle_start", "angle", psi_start),
            ("angle_end", "angle", psi_end),
            ("rotation_start", "angle", psi_start - und.node_psi[0]),
            ("rotation_end", "angle", psi_end - und.node_psi[-1]),
            ("length", "length", link_properties(ctx, t).length),
            ("x_end_undeformed", "length", und.node_position[-1][0]),
            ("y_end_undeformed", "length", und.node_position[-1][1]),
            ("energy", "energy", energy),
        ]
        outputs += _end_outputs(ctx, t, elongation, m_start, m_end)
        deformed = _ordered(nodes, points, s.kinematics)
        undeformed = _ordered(und.node_position, [q.position for q in und.contact_points], und)
        half = link_properties(ctx, t).half_thickness
        thickness = [half(ca.SX(u)) for u in _ordered_u(s.kinematics)] if half is not None else None
        return Contribution(
            {i: on_start, j: on_end}, rows, outputs, energy, CentreLine(deformed, undeformed, thickness)
        )

    def stress_along(self, P, t: LinkElementsTopology, outputs: dict[str, float], points) -> np.ndarray | None:
        """The bending stress at each drawn point, nodes and contact points in u order
        (models.elements.fibre_stress), from the end conditions' reactions: exact statics of
        the discrete solution, where the curvature of its rotations is one order less accurate."""
        rule, h = element_rule(t.degree), 1.0 / t.intervals
        inner = [e * h + h * xi for e in range(t.intervals) for xi in rule.at_contact.xi]
        us = sorted([k * h for k in range(t.intervals + 1)] + inner)
        return link_stresses(P, t, outputs, points, us) if len(us) == len(points) else None

    def unknowns(self, t: LinkElementsTopology) -> list[tuple[str, str]]:
        first = 0 if t.start == "pinned" else 1
        names = [(f"theta{k}", "angle") for k in range(first, t.intervals * t.degree + 1)]
        for field_name, present in (("gamma", t.shear), ("eps", t.axial)):
            if present:
                names += [(f"{field_name}{k}", "dimensionless") for k in range(t.intervals * t.degree)]
        names += [("end.lambda_x", "force"), ("end.lambda_y", "force")]
        if t.end == "clamped":
            names.append(("end.lambda_moment", "moment"))
        return names

    def kinetic_energy(self, ctx, t: LinkElementsTopology, d, v):
        if t.weighs:
            raise NoMassForm(
                "its mass moves with its own variables, which the residual form's mass matrix does not "
                "see: the dynamics form (models.graph.dynamics) carries it"
            )
        return None

    def scale_hint(self, t: LinkElementsTopology, values: SiValues) -> ScaleHint:
        return LINK.scale_hint(t, values)


def _density_and_I(ctx: AssemblyContext, t: LinkElementsTopology):
    return ctx.P[f"/materials/{t.material}/density"], section_properties(ctx.P, t.section).I


def _normal(psi: ca.SX) -> ca.SX:
    return ca.vertcat(-ca.sin(psi), ca.cos(psi))


def _ordered_u(kin: LinkKinematics) -> list[float]:
    return sorted([*kin.node_u, *[q.u for q in kin.contact_points]])


def _ordered(nodes: list[ca.SX], points: list[ca.SX], kin: LinkKinematics) -> list[ca.SX]:
    """Nodes and quadrature points in the order of u, for drawing."""
    tagged = [(u, x) for u, x in zip(kin.node_u, nodes)] + [(q.u, x) for q, x in zip(kin.contact_points, points)]
    return [x for _, x in sorted(tagged, key=lambda pair: pair[0])]


LINK_ELEMENTS = LinkElementsFamily()


def _end_outputs(ctx: AssemblyContext, t: LinkElementsTopology, elongation, m_start, m_end) -> list:
    """The elongation (with axial strain) and the bending stress at the ends, where a clamped
    flexure's peaks (with a section that has an outer fibre)."""
    outputs = [("elongation", "length", elongation)] if t.axial else []
    fibre = link_properties(ctx, t).fibre
    if fibre is not None:
        outputs.append(("stress_start", "stress", ca.fabs(m_start) * fibre(ca.SX(0.0))))
        outputs.append(("stress_end", "stress", ca.fabs(m_end) * fibre(ca.SX(1.0))))
    return outputs
