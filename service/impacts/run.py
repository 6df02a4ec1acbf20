"""An impact simulation of a document (scheme event_driven or moreau): costed before it
starts, the start state checked, the integration, and its report (service.impacts.report)."""

from __future__ import annotations

import json
import threading
from collections import OrderedDict

import numpy as np

from flexmech.models import MechanismError
from flexmech.models.contact.laws import FRICTION_LAWS, NORMAL_LAWS, check_law
from flexmech.models.contact.schema import FrictionFields
from flexmech.models.documents.document import MechanismDocument
from flexmech.models.documents.simulation_spec import SimulateSpec
from flexmech.models.impacts.model import DAMPING, WORKS, ImpactModel, impact_model
from flexmech.models.units import document_unit, quantity_to_si
from flexmech.service.dynamics.histories import history_expression
from flexmech.service.impacts.event_driven import EventLayout
from flexmech.service.impacts.report import Histories, RunStopped, depth_function, histories, report
from flexmech.service.impacts.state_sensitivity import check_fields, end_state_derivatives, parameter_directions
from flexmech.service.impacts.stepping import KEPT_EVENT_ROWS, Trace, run_events, run_moreau

TRIALS_PER_STEP = 4  # event-driven: trial steps allowed per allowed step (rejections, event location)
MAX_STEP_PARTS = 500  # event-driven: the default longest step, a part of the run (smooth histories to draw)
HELD_COPIES = 3  # copies of each state number while a report is made (check_memory)


def timed_fields(document: MechanismDocument, spec: SimulateSpec) -> list[tuple[str, str, object]]:
    """(pointer, where, t -> SI value) per history of `simulate/histories` (loads, gravity)."""
    out = []
    for path, history in spec.histories.items():
        pointer = path if path.startswith("/") else f"/{path}"
        where = f"/simulate/histories/{pointer.lstrip('/').replace('~', '~0').replace('/', '~1')}"
        kind = (
            "acceleration" if pointer.startswith("/gravity/") else "moment" if pointer.endswith("/moment") else "force"
        )
        factor = quantity_to_si(1.0, kind, document_unit(document.units, kind), where)

        def value(t, history=history, where=where, factor=factor):
            return history_expression(history, t, where, spec.until) * factor

        out.append((pointer, where, value))
    return out


def check_laws(model: ImpactModel, spec: SimulateSpec) -> None:
    """Each pair's laws are ones the scheme takes (models.contact.laws): penalty laws and
    Ambrosio's friction for event_driven, restitution and Coulomb's friction for moreau."""
    for pair in model.pairs:
        base = f"/contacts/pairs/{pair.name}"
        check_law(NORMAL_LAWS, "normal", pair.law, spec.scheme, f"{base}/normal/law")
        written = model.book.document.contacts.pairs[pair.name].friction
        check_law(
            FRICTION_LAWS,
            "friction",
            pair.friction,
            spec.scheme,
            f"{base}/friction/law" if isinstance(written, FrictionFields) else f"{base}/friction",
        )


def start_state(model: ImpactModel, spec: SimulateSpec, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(q0, v0) in SI from `simulate/initial`, refusing a start that penetrates a surface."""
    book, n = model.book, model.bodies.size
    q0, v0 = np.zeros(n), np.zeros(n)
    kinds = ("length", "length", "angle")
    for name, start in spec.initial.items():
        pointer = f"/simulate/initial/{name}"
        body = model.bodies.body(name, pointer)
        if body.first is None:
            raise MechanismError(pointer, f"body '{name}' is fixed: it has no start state")
        for k, kind in enumerate(kinds):
            q0[body.first + k] = book.si(start.displacement[k], kind, f"{pointer}/displacement/{k}")
            v0[body.first + k] = book.si(start.velocity[k], kind, f"{pointer}/velocity/{k}")
    depth = depth_function(model)
    pens = np.asarray(depth(q0, 0.0, p)).ravel()
    for pair, pen in zip(model.pairs, pens):
        if pen > 0:
            where = next((f"/simulate/initial/{name}" for name in spec.initial), "/simulate/initial")
            raise MechanismError(
                where,
                f"the start state penetrates: pair '{pair.name}' overlaps by "
                f"{pen / book.si(1.0, 'length', where):.6g} {book.document.units.length}; "
                "start the bodies apart",
            )
    return q0, v0


MODELS_KEPT = 16  # impact models kept per thread, by document: building one costs as much as a second of stepping
_MODELS: OrderedDict[tuple, ImpactModel] = OrderedDict()
_CACHES = threading.Lock()  # threads share the dictionary, never their CasADi objects


def model_of(document: MechanismDocument, spec: SimulateSpec) -> ImpactModel:
    """The impact model of a document and its histories, built once per thread (a thread
    never shares CasADi objects with another). The end time is part of the key: building
    checks each history is finite up to it."""
    histories = json.dumps(spec.histories, sort_keys=True)
    key = (document.model_dump_json(), histories, spec.until, threading.get_ident())
    with _CACHES:
        model = _MODELS.get(key)
        if model is not None:
            _MODELS.move_to_end(key)
            return model
    model = impact_model(document, timed_fields(document, spec), histories)
    with _CACHES:
        if len(_MODELS) >= MODELS_KEPT:
            _MODELS.popitem(last=False)
        _MODELS[key] = model
    return model


def run_impacts(
    document: MechanismDocument,
    spec: SimulateSpec,
    stop=None,
    max_steps: int = 2_000_000,
    parameters: dict[str, float] | None = None,
    progress=None,
    max_kept: int | None = None,
    max_bytes: int | None = None,
) -> tuple[Trace, dict]:
    """(the raw trace, the report). `parameters` replaces numbers (SI) by their pointers;
    `max_kept` bounds the states a report keeps below `max_points` (one response); `max_bytes`
    the memory the run's states may take (check_memory)."""
    model, p, trace = integrate(document, spec, stop, max_steps, parameters, progress, max_bytes)
    answer = report(model, spec, trace, p, max_kept)  # trace.seconds: the stepping alone
    if trace.derivatives is not None:
        answer["sensitivities"] = end_state_derivatives(model, trace, spec.sensitivities, answer["events"])
    return trace, answer


def run_with_histories(
    document: MechanismDocument, spec: SimulateSpec, stop=None, max_steps: int = 2_000_000
) -> tuple[Histories | None, dict]:
    """(the histories at every state the run holds, the report); a run `stop` ended has no
    histories (None) and a report of its status alone: evaluating the contacts at its states
    takes seconds (two million states), which a cancel must not wait for."""
    model, p, trace = integrate(document, spec, stop, max_steps)
    if trace.status == "stopped":
        return None, {"status": "stopped", "message": trace.message, "seconds": trace.seconds}
    try:
        full = histories(model, spec, trace, p, stop)
    except RunStopped as stopped:  # stop() came while its states were evaluated
        return None, {"status": "stopped", "message": str(stopped), "seconds": trace.seconds}
    return full, report(model, spec, trace, p, full=full)


def integrate(
    document: MechanismDocument,
    spec: SimulateSpec,
    stop=None,
    max_steps: int = 2_000_000,
    parameters: dict[str, float] | None = None,
    progress=None,
    max_bytes: int | None = None,
) -> tuple[ImpactModel, np.ndarray, Trace]:
    """(the model, its parameter vector, the trace of the run)."""
    check_cost(spec, max_steps)
    model = model_of(document, spec)
    if max_bytes is not None:
        check_memory(model, spec, max_bytes)
    values = np.array(model.book.values)
    values[model.book.pointers.index(DAMPING)] = spec.damping
    for pointer, value in (parameters or {}).items():
        values[model.book.pointers.index(pointer)] = value
    p = model.book.parameter_vector(values)
    check_laws(model, spec)
    q0, v0 = start_state(model, spec, p)
    directions = None
    if spec.sensitivities:
        check_fields(model.book, spec.sensitivities, spec.histories)
        directions = parameter_directions(model.book, values, spec.sensitivities)
    if spec.scheme == "moreau":
        trace = run_moreau(model, p, q0, v0, spec.until, spec.step, stop, progress)
    else:
        max_step = spec.max_step if spec.max_step is not None else spec.until / MAX_STEP_PARTS
        trace = run_events(
            model,
            p,
            q0,
            v0,
            spec.until,
            spec.tolerance,
            spec.step,
            max_step,
            max_steps * TRIALS_PER_STEP,
            stop,
            progress,
            directions,
        )
    return model, p, trace


def held_bytes(model: ImpactModel, spec: SimulateSpec) -> int:
    """About the memory a run's states take at their peak: every Moreau step's state and
    impulses (an event-driven run holds at most KEPT_EVENT_ROWS states), about three copies
    of each number while the report is made (measured: 360 bytes a step for the CSFH's 17)."""
    n, P, pins = model.bodies.size, len(model.pairs), model.constraints.numel()
    if spec.scheme == "moreau":
        rows, columns = round(spec.until / spec.step) + 1, 1 + 2 * n + len(WORKS) + 5 * P + pins
    else:
        rows, columns = KEPT_EVENT_ROWS, EventLayout(n, P).size
    return HELD_COPIES * 8 * rows * columns


def check_memory(model: ImpactModel, spec: SimulateSpec, max_bytes: int) -> None:
    needed = held_bytes(model, spec)
    if needed > max_bytes:
        raise MechanismError(
            "/simulate/until",
            (
                f"{spec.until:g} s of {spec.scheme} steps of {spec.step:g} s would hold about {needed / 2**20:.0f} MiB "
                f"of states, over the {max_bytes / 2**20:.0f} MiB one run may take: simulate a shorter time or take a "
                "longer step"
            ),
        )


def check_cost(spec: SimulateSpec, max_steps: int) -> None:
    """Refuse a run over the step limit before it starts: Moreau's fixed steps; an event-driven
    run costed at its first step (its steps adapt, and the integrator also stops at the limit)."""
    if spec.scheme == "moreau":
        steps = round(spec.until / spec.step)
        if steps < 1:
            raise MechanismError(
                "/simulate/step", f"the step {spec.step:g} s is longer than the run ({spec.until:g} s)"
            )
        if steps > max_steps:
            raise MechanismError(
                "/simulate/step",
                f"the run needs {steps} steps of {spec.step:g} s, over the limit "
                f"of {max_steps}: take a longer step or a shorter run",
            )
        return
    costed = spec.until / spec.step
    if costed > max_steps:
        raise MechanismError(
            "/simulate/until",
            (
                f"{spec.until:g} s from a first step of {spec.step:g} s is costed at {costed:.3g} steps, over the "
                f"limit of {max_steps}: event-driven steps adapt (scenario 6.3 takes about 1700 a second), but a run "
                "is costed before it starts at its first step; simulate a shorter time or take a longer first step"
            ),
        )
