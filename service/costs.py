"""What a request costs, counted before anything is allocated or built, against the limits.

The work of building a structure's graphs grows with its links: each shooting interval
unrolls the integrator, about order^2 evaluations of the link's equations, and a build costs
about 0.6 ms per unit of intervals x order^2 on a 2-core machine (8 links of 64 intervals of
order 12 took 113 s). Counts of bodies, elements, loads and outputs, and the size of what a
job stores, are bounded the same way. Every refusal names the field and the limit.
"""

from __future__ import annotations

from dataclasses import dataclass

from flexmech.models import MechanismError
from flexmech.models.documents.document import MechanismDocument
from flexmech.models.elements import FAMILIES
from flexmech.models.elements.base import Discretization


@dataclass(frozen=True)
class Limits:
    max_elements: int = 200
    max_sweep_points: int = 20_000
    solve_time_limit: float | None = 10.0
    max_bodies: int = 200
    max_loads: int = 500
    max_outputs: int = 500  # named outputs of a document
    max_link_work: int = 8192  # intervals x order^2, summed over links (and exact curved beams)
    # intervals of one link by elements (a document takes 128: their kernels do, but every analysis
    # also builds the dense statics graph, whose size grows with the chain: 32 cubic elements 10 s)
    max_link_elements: int = 64
    max_result_values: int = 1_000_000  # numbers a job stores: points x values per point
    job_time_limit: float | None = 3600.0
    max_contact_rows: int = 2000  # non-penetration rows of a contact problem (an upper estimate)
    max_contact_rotations: int = 128  # rotations of the links (intervals x degree, summed) of a contact problem
    max_simulation_steps: int = 1_000_000  # time steps of a simulation job
    max_export_unknowns: int = 400  # unknowns of an exported C library (its C grows about 10 kB per unknown)
    max_response_bytes: int = 20_000_000  # the JSON of one /v1/solve answer (larger: an analysis job, stored)


def discretizations(doc: MechanismDocument, model: str | None) -> list[tuple[str, Discretization]]:
    """(element, what its unknowns cost) of every element with unknowns of its own, as its
    family says (models.elements.base.Discretization)."""
    out = []
    for name, element in doc.elements.items():
        ask = getattr(FAMILIES.named(element.type), "discretization", None)
        cost = ask(element, model) if ask is not None else None
        if cost is not None:
            out.append((name, cost))
    return out


def link_work(doc: MechanismDocument, model: str | None) -> list[tuple[str, int]]:
    """(element, intervals x order^2) of every element solved by shooting; a link by elements:
    intervals x (degree + 2)^2, its quadrature and contact points' work alike."""
    return [(name, cost.work) for name, cost in discretizations(doc, model)]


def check_contact_rotations(doc: MechanismDocument, limits: Limits, prefix: str) -> None:
    """A contact problem's exact KKT matrix is dense in the links' rotations (a contact point
    moves with every rotation before it): building it grows with their square, about 4 s for
    96 rotations here."""
    total = 0
    for name, cost in discretizations(doc, None):
        total += cost.rotations
        if total > limits.max_contact_rotations:
            raise MechanismError(
                f"{prefix}/elements/{name}/intervals",
                (
                    f"a contact problem's links have at most {limits.max_contact_rotations} rotations "
                    f"(intervals x degree, summed), these have more; use fewer elements (8 cubic ones "
                    "reach 1e-9 on a finger) or a lower degree"
                ),
            )


def contact_rows(doc: MechanismDocument) -> list[tuple[str, int]]:
    """(pair, an upper estimate of its non-penetration rows): a surface's contact points, a
    jaw's vertices (8 per edge against an implicit curve; times the object's vertices against
    a polygon, whose convex pieces each need a separating line)."""
    contacts = doc.contacts
    if contacts is None:
        return []
    out = []
    for name, pair in contacts.pairs.items():
        site, obj = contacts.sites.get(pair.site), contacts.objects.get(pair.object)
        if site is None or obj is None:
            continue  # the compiler names the reference
        if site.type == "surface":
            link = doc.elements.get(site.link)
            rows = getattr(link, "intervals", 1) * getattr(link, "degree", 1) + 2
        elif site.type == "circle":
            rows = 1
        else:
            rows = len(site.vertices) * (8 if obj.type == "implicit" else 1)
            if obj.type == "polygon":
                rows *= 2 * len(obj.vertices)
        out.append((name, rows))
    return out


def check_document_cost(doc: MechanismDocument, model: str | None, limits: Limits, prefix: str = "/document") -> None:
    """MechanismError (under `prefix`) where the document exceeds a limit."""
    for collection, limit in (
        ("bodies", limits.max_bodies),
        ("elements", limits.max_elements),
        ("loads", limits.max_loads),
        ("outputs", limits.max_outputs),
    ):
        count = len(getattr(doc, collection))
        if count > limit:
            raise MechanismError(f"{prefix}/{collection}", f"{count} {collection}: the limit is {limit}")
    for name, cost in discretizations(doc, model):
        if cost.elements > limits.max_link_elements:
            raise MechanismError(
                f"{prefix}/elements/{name}/intervals",
                (
                    f"{cost.elements} elements: the service takes at most {limits.max_link_elements} in one link "
                    "(its statics graph is built in the request); use fewer elements or a higher degree"
                ),
            )
    total = 0
    for name, work in link_work(doc, model):
        total += work
        if total > limits.max_link_work:
            raise MechanismError(
                f"{prefix}/elements/{name}/intervals",
                (
                    f"the links need {sum(w for _, w in link_work(doc, model))} units of graph work (intervals x "
                    f"order^2, summed): the limit is {limits.max_link_work}; use fewer intervals or a lower order"
                ),
            )
    if doc.contacts is not None:
        check_contact_rotations(doc, limits, prefix)
    total = 0
    for name, rows in contact_rows(doc):
        total += rows
        if total > limits.max_contact_rows:
            raise MechanismError(
                f"{prefix}/contacts/pairs/{name}",
                (
                    f"the contact pairs need about {sum(r for _, r in contact_rows(doc))} non-penetration rows: the limit "
                    f"is {limits.max_contact_rows}; use fewer pairs, vertices or elements"
                ),
            )


def check_grid_size(counts: list[int], limits: Limits, pointer: str = "/parameters") -> int:
    """The number of points of a cartesian grid of `counts` values per axis, counted with
    Python integers (exact, no overflow) before any value is made."""
    total = 1
    for count in counts:
        total *= count
    if total > limits.max_sweep_points:
        raise MechanismError(pointer, f"{total} sweep points: the limit is {limits.max_sweep_points}")
    return total


# What building an export costs, predicted from the mechanism's elements before any code is
# generated (service.export.size_model, fitted to python3 -m benchmarks.export_size): gcc -O2's time
# and memory grow about as the square of the largest generated function (a link's own rows), so
# neither the C's size nor the unknowns bound them. A builder takes 60 s and 1 GB on 2 cores: the
# predicted build stays within these less the model's error on the measured links (-19% in memory;
# -31% in time for a link of order 4, where the memory binds first, else -24%): the largest links it
# takes built in 41 s and 863 MB at most. A function above the model's measured range is refused.
EXPORT_BUILD_SECONDS = 45.0
EXPORT_BUILD_MEGABYTES = 800.0


def check_export_build(mech, pointer: str = "/document/elements") -> None:
    """The export of a compiled mechanism (models.Mechanism) within EXPORT_BUILD_SECONDS and
    EXPORT_BUILD_MEGABYTES of gcc -O2 as predicted, else MechanismError saying the predicted C
    size, compile time and memory, and what drives them."""
    from flexmech.service.export.size_model import BODY_ROWS, predicted_size

    size = predicted_size(mech.structure)
    over = build_over_limits(size)
    if over is None:
        return
    change = (
        "use fewer elements"
        if size.largest.what == BODY_ROWS
        else "use fewer intervals or a lower order (degree), or split the link in two at a body"
    )
    raise MechanismError(pointer, f"{over}; {change}")


def build_over_limits(size) -> str | None:
    """None when an export's predicted build (service.export.size_model.ExportSize) is within
    the limits, else what it would write and take, against them."""
    from flexmech.service.export.size_model import GCC_PREDICTED_UP_TO

    fits = size.gcc_seconds <= EXPORT_BUILD_SECONDS and size.gcc_megabytes <= EXPORT_BUILD_MEGABYTES
    if fits and not size.beyond:
        return None
    largest = size.largest
    build = f"about {size.gcc_seconds:.0f} s and {size.gcc_megabytes:,.0f} MB to build it"
    if size.beyond:  # gcc's regime there is its own choice: the faster one's figures, or minutes
        build += (
            " if it drops its quadratic passes for a function this large (as for a link of 56 x 12), far more if not"
        )
    else:
        build += " (a function's build grows about as the square of its size)"
    return (
        f"an export of this mechanism writes about {size.c_bytes / 1e6:.1f} MB of C, with {largest.what} in one "
        f"function of about {largest.instructions:,} instructions: gcc -O2 needs {build}; the limit is "
        f"{EXPORT_BUILD_SECONDS:.0f} s and {EXPORT_BUILD_MEGABYTES:.0f} MB as predicted, and functions of at most "
        f"{GCC_PREDICTED_UP_TO:,} instructions (a builder's 60 s and 1 GB, less the prediction's error)"
    )


def check_export_unknowns(unknowns: int, limits: Limits, pointer: str = "/document/elements") -> None:
    """An export's unknowns: its stiffness task condenses them densely and its check runs the
    kernels over them (check_export_iteration); writing 582 took 61 s. What its build costs is
    check_export_build's."""
    if unknowns > limits.max_export_unknowns:
        raise MechanismError(
            pointer,
            f"{unknowns} unknowns: an export takes at most {limits.max_export_unknowns}; use fewer elements or "
            "intervals (a curved beam's partial_nonlinear model adds none)",
        )


# What checking an export costs: its Python twin of the C iteration runs over the example path
# (service.export.measure), warm and cold at each point, each run at most 1 + max_iterations x
# (line_search_halvings + 1) kernel calls. A call took 52 us for the gripper (9 unknowns) and
# 394 us for gripper_exact (137), about 28 + 2.7 x unknowns us.
EXPORT_CHECK_SECONDS = 60.0  # the worst case the check may take
EXPORT_PATH_POINTS = 100  # points of the example path (service.export.sources.ExamplePath)
EXPORT_RUNS_PER_POINT = {"equilibrium": 2, "contact": 4}  # warm and cold; contact falls back to cold
TWIN_CALL_SECONDS, TWIN_CALL_SECONDS_PER_UNKNOWN = 28e-6, 2.7e-6
# A nondimensional residual of order one reaches about 1e-15 in double precision, reliably 1e-14:
# below that a Newton run never converges and runs to max_iterations at every point.
MIN_EXPORT_TOLERANCE = 1e-14


def check_export_iteration(unknowns: int, max_iterations: int, halvings: int, tolerance: float, contact: bool) -> None:
    """An export's iteration options, costed: a tolerance double precision can reach, and the
    worst case of checking it over the example path within EXPORT_CHECK_SECONDS."""
    if tolerance < MIN_EXPORT_TOLERANCE:
        raise MechanismError(
            "/tolerance",
            f"{tolerance:g} is below what double precision reaches (a nondimensional |R|_inf of about "
            f"{MIN_EXPORT_TOLERANCE:g}): give at least {MIN_EXPORT_TOLERANCE:g}",
        )
    runs = EXPORT_PATH_POINTS * sum(EXPORT_RUNS_PER_POINT[t] for t in ("equilibrium", "contact")[: 1 + contact])
    calls = runs * (1 + max_iterations * (halvings + 1))
    seconds = calls * (TWIN_CALL_SECONDS + TWIN_CALL_SECONDS_PER_UNKNOWN * unknowns)
    if seconds > EXPORT_CHECK_SECONDS:
        pointer = "/max_iterations" if max_iterations > 30 or halvings <= 6 else "/line_search_halvings"
        raise MechanismError(
            pointer,
            f"{max_iterations} Newton steps x {halvings + 1} line-search trials x {runs} runs over the example path "
            f"= {calls} kernel calls of {unknowns} unknowns to check the export, about {seconds:.0f} s at worst: "
            f"the limit is {EXPORT_CHECK_SECONDS:.0f} s; ask fewer steps or halvings",
        )


def check_result_size(points: int, per_point: int, limits: Limits, pointer: str = "/outputs") -> None:
    if points * per_point > limits.max_result_values:
        raise MechanismError(
            pointer,
            f"{points} points x {per_point} stored values = {points * per_point}: the "
            f"limit is {limits.max_result_values}; keep fewer outputs or points",
        )


# The longest a float64 takes in JSON with its separator (-1.2345678901234567e-308,): a report's
# numbers times this bounds its encoded size from above, whatever the values turn out to be.
BYTES_PER_NUMBER = 25
ANALYSIS_JOBS = "POST /v1/analysis-jobs"  # where a report too large to answer runs, stored


def _megabytes(count: int) -> str:
    return f"{count / 1e6:.3g} MB"


def check_report_size(size, limits: Limits, answered: bool = True) -> None:
    """MechanismError at the field that drives a report's size (service.analyses.base.ReportSize)
    when its numbers cannot be answered in one response (`answered`: /v1/solve) or stored by a
    job, saying what to change."""
    stored_ok = size.numbers <= limits.max_result_values
    encoded = size.numbers * BYTES_PER_NUMBER
    if answered and encoded > limits.max_response_bytes:
        counted = (
            f"the report would hold {size.numbers} numbers ({size.terms}), up to {_megabytes(encoded)} of JSON: an "
            f"answer is at most {_megabytes(limits.max_response_bytes)}"
        )
        if stored_ok:
            message = (
                f"{counted}; {size.change}, or run it as a job ({ANALYSIS_JOBS} with the same body), whose report is "
                f"stored (up to {limits.max_result_values} numbers)"
            )
        else:
            message = f"{counted} and a job stores at most {limits.max_result_values} numbers; {size.change}"
        raise MechanismError(size.pointer, message)
    if not answered and not stored_ok:
        raise MechanismError(
            size.pointer,
            f"the report would hold {size.numbers} numbers ({size.terms}): a job stores at most "
            f"{limits.max_result_values}; {size.change}",
        )


def check_response_bytes(encoded: int, limits: Limits, pointer: str) -> None:
    """The answer as encoded, against the bound: the count before the work is an estimate (a
    name's length, an impact run's onsets), this is the measure."""
    if encoded > limits.max_response_bytes:
        raise MechanismError(
            pointer,
            f"the report is {_megabytes(encoded)} of JSON: an answer is at most "
            f"{_megabytes(limits.max_response_bytes)}; ask for less, or run it as a job ({ANALYSIS_JOBS})",
        )
