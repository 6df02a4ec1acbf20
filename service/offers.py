"""What a document can be asked: per analysis of /v1/solve and per job kind, None when it
applies, else why not, in the words its own refusal would use. Only the checks that read the
document and its structure run here (no graph is built, no state solved), so the workbench asks
on every document it draws and offers in its Run menu only what the service would run.

The reasons come from the analyses' and jobs' own preconditions:
  - rigid bodies in clearances (a document whose simulate scheme is an impact scheme) have no
    static state: only the simulate analysis and the impact study apply;
  - energy and contact need an energy form of every element (models.elements: a curved beam's
    conservative model, a link by elements);
  - contact (and the contact path job) needs contact pairs;
  - time and vibration need mass; link dynamics (simulate, the simulation job) an end time;
  - the optimization job needs an optimize section.
"""

from __future__ import annotations

from collections.abc import Callable

from flexmech.models import Mechanism, MechanismError
from flexmech.models.documents.simulation_spec import IMPACT_SCHEMES
from flexmech.models.graph.forms import energy_form_problem
from flexmech.service.analyses import ANALYSES

Check = Callable[[Mechanism], str | None]


def _impact_scheme(mech: Mechanism) -> str | None:
    section = mech.document.simulate
    scheme = getattr(section, "scheme", None) if section is not None else None
    return scheme if scheme in IMPACT_SCHEMES else None


def _statics(mech: Mechanism) -> str | None:
    scheme = _impact_scheme(mech)
    if scheme:
        return f"the document is an {scheme} impact simulation of rigid bodies in clearances: it has no static state"
    return None


def _energy(mech: Mechanism) -> str | None:
    return _statics(mech) or energy_form_problem(mech.structure)


def _pairs(mech: Mechanism) -> str | None:
    contacts = mech.document.contacts
    if contacts is None or not contacts.pairs:
        return "the document has no contact pairs"
    return None


def _contact(mech: Mechanism) -> str | None:
    return _statics(mech) or _pairs(mech) or energy_form_problem(mech.structure)


def _some_mass(mech: Mechanism) -> str | None:
    document = mech.document
    weighed = any(getattr(body, "mass", None) for body in document.bodies.values())
    dense = any(getattr(material, "density", None) for material in (document.materials or {}).values())
    if not (weighed or dense):
        return "the mechanism has no mass: give a body a mass or a material a density"
    return None


def _mass(mech: Mechanism) -> str | None:
    """Mass where link dynamics integrates: every element it steps carries its own."""
    from flexmech.service.dynamics.run import check_masses

    missing = _some_mass(mech)
    if missing or _impact_scheme(mech):  # rigid bodies in clearances: their own masses, no elements stepped
        return missing
    try:
        check_masses(mech)
    except MechanismError as exc:
        return exc.problem
    return None


def _simulate(mech: Mechanism) -> str | None:
    section = mech.document.simulate
    if section is None or getattr(section, "until", None) is None:
        return "the document has no simulate section with an end time `until`"
    return _mass(mech)


def _simulation_job(mech: Mechanism) -> str | None:
    scheme = _impact_scheme(mech)
    if scheme:
        return f"an {scheme} impact simulation runs as the simulate analysis (its second of motion takes milliseconds)"
    return _simulate(mech)


def _impact_study(mech: Mechanism) -> str | None:
    if not _impact_scheme(mech):
        return f"an impact study runs an impact scheme ({', '.join(IMPACT_SCHEMES)}) of the simulate section"
    return None


def _vibration(mech: Mechanism) -> str | None:
    return _statics(mech) or _some_mass(mech)  # massless elements are condensed


def _optimization(mech: Mechanism) -> str | None:
    if mech.document.optimize is None:
        return "the document has no optimize section"
    return _statics(mech)


def _tolerances(mech: Mechanism) -> str | None:
    if mech.document.tolerances is None:
        return "the document has no tolerances section"
    return _statics(mech)


ANALYSIS_CHECKS: dict[str, Check] = {
    "equilibrium": _statics,
    "linearization": _statics,
    "trace": _statics,
    "inverse": _statics,
    "energy": _energy,
    "contact": _contact,
    "simulate": _simulate,
    "modes": _vibration,
    "frequency_response": _vibration,
    "tolerance": _tolerances,
}
JOB_CHECKS: dict[str, Check] = {
    "sweep": _statics,
    "optimize": _optimization,
    "contact": _contact,
    "simulation": _simulation_job,
    "impact_study": _impact_study,
    "export": _statics,
}


def offers(mech: Mechanism) -> dict[str, dict[str, str | None]]:
    """{"analyses": {name: None or why not}, "jobs": {operation: ...}}, a job kind by the name of
    its POST's operation (contact_path for POST /v1/contact-paths); an analysis or a job kind of
    a plugin, with no check here, is offered."""
    analyses = {a.name: ANALYSIS_CHECKS.get(a.name, lambda _: None)(mech) for a in ANALYSES}
    from flexmech.service.jobs.kinds import job_kinds

    jobs = {
        getattr(kind, "operation_id", name).removeprefix("create_"): JOB_CHECKS.get(name, lambda _: None)(mech)
        for name, kind in job_kinds().items()
    }
    return {"analyses": analyses, "jobs": jobs}
