"""The contact analysis of one state: the minimum of the total potential under
non-penetration (service.contact), its contact forces from the multipliers, friction when
the request says how the objects move (`motion`: the rates of the moving fields; a path job
gives friction its direction from the path), sensitivities, and the thesis' recovery as a
labelled comparison. A quasi-static path is the contact job (service.jobs.contact)."""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field

from flexmech.models import Mechanism, MechanismError
from flexmech.models.documents.fields import Pointer
from flexmech.service.analyses.base import (
    Analysis,
    AnalysisOptions,
    AnalysisResult,
    ReportSize,
    drawn_numbers,
    state_numbers,
)
from flexmech.service.analyses.shared_options import Sensitivities
from flexmech.service.contact.drawing import state_drawing
from flexmech.service.contact.problem import ContactProblem, contact_problem
from flexmech.service.contact.recovery import recovered_forces
from flexmech.service.contact.report import friction_coefficients, penetration_error, state_report
from flexmech.service.contact.sensitivity import contact_sensitivities
from flexmech.service.contact.solve import ContactOptions, PenetratingStart, solve_state
from flexmech.service.requests import under
from flexmech.service.solvers.newton import NewtonOptions
from flexmech.service.solvers.reports import output_units, plain


def problem_of(mech: Mechanism) -> ContactProblem:
    try:
        return contact_problem(mech.structure)
    except MechanismError as exc:
        raise under("/document", exc) from None


def motion_rates(mech: Mechanism, motion: dict, p: np.ndarray) -> np.ndarray:
    """The nondimensional rate of p (document rates per field), scaled to a largest entry 1."""
    rates = np.zeros_like(p)
    for path, rate in motion.items():
        try:
            k = mech.parameter_index(path)
        except MechanismError as exc:
            raise MechanismError(f"/motion/{path.lstrip('/')}", f"'{path}' is {exc.problem}") from None
        rates[k] = float(rate) * mech.nd_per_doc(mech.parameters[k].kind)
    size = float(np.abs(rates).max(initial=0.0))
    if size == 0:
        raise MechanismError("/motion", "the motion moves nothing: give a nonzero rate")
    return rates / size


class ContactAnalysisOptions(AnalysisOptions):
    penetrating_start: Literal["approach", "refuse"] = Field(
        "approach",
        description="an object inside a site in the undeformed state is approached from outside "
        "(relaxed, then tightened in steps), or refused naming the pair and depth",
    )
    motion: dict[Pointer, float] | None = Field(
        None,
        max_length=64,
        description="how the moving fields change (document units per unit of progress): "
        "friction opposes the sliding this motion causes",
        examples=[{"/contacts/objects/fixture/centre/0": -1}],
    )
    sensitivities: Sensitivities | None = Field(None, description="also d(outputs)/d(parameters) at the state")
    thesis_recovery: bool = Field(
        False,
        description="also the thesis' recovery of the forces from the "
        "frictionless shape (Lan 2005 Eqs. 6.6-6.10), labelled",
    )


class ContactReport(AnalysisResult):
    pairs: dict[str, dict] = Field(default_factory=dict, description="every pair's state and forces")
    units: dict[str, str] = Field(default_factory=dict, description="the units of the pairs' numbers")
    kkt_residual: float | None = Field(None, description="the largest residual of its KKT system (force unit)")


class ContactAnalysis(Analysis):
    name = "contact"
    summary = (
        "The minimum of the total potential under non-penetration by IPOPT: contact forces from the "
        "multipliers, friction along a given motion, sensitivities"
    )

    long = True
    Options = ContactAnalysisOptions
    Result = ContactReport

    def report(self, mech: Mechanism, newton: NewtonOptions, given: ContactAnalysisOptions) -> dict:
        problem = problem_of(mech)
        options = ContactOptions(given.penetrating_start, newton.time_limit)
        p, mu = mech.p(), friction_coefficients(mech, problem)
        motion = given.motion
        try:
            rates = motion_rates(mech, motion, p) if motion else None
            state = solve_state(problem, p, mu, options=options, motion=rates)
        except PenetratingStart as error:
            raise penetration_error(mech, error) from None
        report = {
            "analysis": self.name,
            "name": mech.document.name,
            **state_report(mech, problem, state),
            "units": {
                "force": mech.doc_unit("force"),
                "length": mech.doc_unit("length"),
                "moment": mech.doc_unit("moment"),
            },
            "output_units": output_units(mech),
            "warnings": [],
            "drawing": state_drawing(mech, problem, state),
        }
        if np.any(mu > 0) and not motion:
            report["warnings"].append(
                "friction needs the direction of sliding: give `motion` (the rates of the "
                "moving fields) or run a contact path; this state is frictionless"
            )
        for name, pair in report["pairs"].items():
            if pair["state"] == "sticking":
                report["warnings"].append(
                    f"pair '{name}' sticks along this motion: its friction force depends on "
                    "the path that led here (run a contact path); none is applied"
                )
        sensitivities = given.sensitivities
        if sensitivities is not None and state.converged:
            found, notes = contact_sensitivities(mech, problem, state, sensitivities.parameters, sensitivities.outputs)
            report["sensitivities"] = found.to_dict()
            report["warnings"] += notes
        if given.thesis_recovery and state.converged:
            plain_state = (
                state if not np.any(mu > 0) else solve_state(problem, p, 0 * mu, previous=state, options=options)
            )
            report["thesis_recovery"] = recovered_forces(mech, state_report(mech, problem, plain_state), report)
        return plain(report)

    def report_size(self, mech: Mechanism, given: ContactAnalysisOptions) -> ReportSize:
        """A state, its drawing, each pair's state and forces, and the sensitivities asked."""
        pairs = len(mech.document.contacts.pairs) if mech.document.contacts is not None else 0
        asked = given.sensitivities
        sensitivities = 2 * len(asked.outputs) * len(asked.parameters) if asked is not None else 0
        return ReportSize(
            2 * state_numbers(mech) + drawn_numbers(mech) + 40 * pairs + sensitivities,
            f"one state and its drawing, {pairs} pairs" + (", sensitivities" if asked is not None else ""),
            "/sensitivities/outputs",
            "ask for fewer sensitivities",
        )


CONTACT = ContactAnalysis()
