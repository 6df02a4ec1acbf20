"""Exact derivatives of an event-driven run's end state with respect to numbers of the
document (a law's stiffness, the restitution, a friction coefficient, a mass, a radius):
forward-mode differentiation of every trial step of the integrator itself
(service.impacts.event_driven), carried along with the state. It is the derivative of the
computed motion: a step that ends at a located event moves with the event, the frozen impact
speed of a contact follows the state it was frozen from, and the step sizes follow their error
estimates. So it equals central differences of the same run wherever the motion depends
smoothly on the number, that is, while no contact event appears, vanishes or changes order.
"""

from __future__ import annotations

import difflib
import threading

import casadi as ca
import numpy as np

from flexmech.models.errors import MechanismError
from flexmech.models.impacts.book import ParameterBook
from flexmech.models.impacts.model import ImpactModel
from flexmech.service.impacts.event_driven import EventLayout, event_step

MAX_CACHED = 8  # chunk Functions kept in memory
GRAZING_SPEED = 1e-6  # m/s: a contact that begins slower touches or misses with any change of the numbers


def sensitivity_step(model: ImpactModel, fields: int) -> ca.Function:
    """(S, dS, p, dp, settings) -> (S1, dS1): one trial step and its forward derivative in
    `fields` directions (dS: d state / d number, one column per number; dp: d p / d number)."""
    step = event_step(model)
    L = EventLayout(model.bodies.size, len(model.pairs))
    S, p = ca.SX.sym("S", L.size), ca.SX.sym("p", model.p.numel())
    dS, dp = ca.SX.sym("dS", L.size, fields), ca.SX.sym("dp", model.p.numel(), fields)
    settings = ca.SX.sym("settings", step.size1_in(2))
    S1 = step(S, p, settings)
    dS1 = ca.jtimes(S1, ca.vertcat(S, p), ca.vertcat(dS, dp))
    return ca.Function(
        "event_sensitivity_step", [S, dS, p, dp, settings], [S1, dS1], ["S", "dS", "p", "dp", "settings"], ["S1", "dS1"]
    )


def parameter_directions(book: ParameterBook, values: np.ndarray, pointers: list[str]) -> np.ndarray:
    """d p / d number (SI) per pointer, one column each: the number's own row and the rows of
    the expressions hoisted from it (a stiffness matrix, a point in body axes)."""
    return book.parameter_jacobian(values)[:, [book.pointers.index(pointer) for pointer in pointers]]


def check_fields(book: ParameterBook, pointers: list[str], driven=()) -> None:
    """Every pointer names a number of the run (one of the graphs' parameters), and not one a
    history drives (`driven`: its value is the history's, not a number)."""
    driven = {pointer if pointer.startswith("/") else f"/{pointer}" for pointer in driven}
    known = [pointer for pointer in book.pointers if pointer not in driven]
    for k, pointer in enumerate(pointers):
        if pointer not in known:
            close = difflib.get_close_matches(pointer, known, n=3)
            hint = (
                f"did you mean {' or '.join(close)}?"
                if close
                else (f"its numbers are {', '.join(known[:12])}{' and more' if len(known) > 12 else ''}")
            )
            raise MechanismError(f"/simulate/sensitivities/{k}", f"'{pointer}' is not a number of this run; {hint}")


def end_state_derivatives(model: ImpactModel, trace, pointers: list[str], events: list[dict]) -> dict:
    """Per field, d (coordinate, velocity at the end time) / d field, in the document's units
    (state) per the field's document unit; and the warnings of a motion that is not
    differentiable (a grazing contact, whose onset time has no derivative)."""
    book, n = model.book, model.bodies.size
    to_si = book.si(1.0, "length", "/units")
    warnings = [
        f"the contact of pair '{event['pair']}' at t = {event['time']:.9g} s begins grazing (impact speed "
        f"{event['impact_speed'] * to_si:.3g} m/s): its onset time has no derivative, and the state after "
        "it may have none (a change of the number can make it touch or miss): check by differences"
        for event in events
        if event["kind"] == "contact" and event["impact_speed"] * to_si < GRAZING_SPEED
    ]
    L = EventLayout(n, len(model.pairs))
    state = trace.derivatives[L.y][: 2 * n]  # SI per SI
    per = {kind: book.si(1.0, kind, "/units") for kind in ("length", "angle")}
    names = model.coordinate_names()
    scale = np.array([per["angle"] if name.endswith(".theta") else per["length"] for name in names])
    units = book.document.units
    fields = {}
    for k, pointer in enumerate(pointers):
        unit, si = book.units.get(pointer, ("SI", 1.0))
        column = state[:, k] * si
        fields[pointer] = {
            "unit": unit,
            "value": book.value(pointer) / si,
            "coordinates": {name: float(column[j] / scale[j]) for j, name in enumerate(names)},
            "velocities": {name: float(column[n + j] / scale[j]) for j, name in enumerate(names)},
        }
    return {
        "time": float(trace.states[0][-1, 0]),
        "fields": fields,
        "warnings": warnings,
        "units": {
            "coordinates": f"{units.length} (x, y) or {units.angle} (theta) per the field's unit",
            "velocities": "those per second",
        },
    }


_CHUNKS: dict[tuple, ca.Function] = {}


class SensitivityChunk:
    """Chunks of trial steps carrying d state / d number along (interpreted: a run with
    sensitivities is a design question, asked far less often than a plain run)."""

    def __init__(self, model: ImpactModel, p: np.ndarray, directions: np.ndarray, settings: np.ndarray, count: int):
        fields = directions.shape[1]
        key = (model.structure_key(), fields, count, threading.get_ident())
        if key not in _CHUNKS:
            if len(_CHUNKS) >= MAX_CACHED:
                _CHUNKS.pop(next(iter(_CHUNKS)))
            _CHUNKS[key] = sensitivity_step(model, fields).mapaccum(
                "event_sensitivity_chunk", count, ["S", "dS"], ["S1", "dS1"]
            )
        self.fn, self.fields = _CHUNKS[key], fields
        self.fixed = [
            ca.DM(np.tile(np.reshape(column, (len(column), -1)), (1, count))) for column in (p, directions, settings)
        ]
        self.derivatives = np.zeros((EventLayout(model.bodies.size, len(model.pairs)).size, fields))

    def run(self, S: np.ndarray) -> list[np.ndarray]:
        states, derivatives = self.fn.call([ca.DM(S), ca.DM(self.derivatives), *self.fixed])
        self.derivatives = np.asarray(derivatives)[:, -self.fields :]
        return [np.asarray(states).T]
