"""The report of an impact simulation (service.impacts.run), in document units: coordinates
and velocities, per pair the contact forces (and Moreau's impulses), the events (contact
onsets and separations, stick/slip transitions) and impacts with their speeds, durations and
peak forces from every state the run holds; the histories, and the energies with what contact
and friction dissipated and the balance, at the kept states (`every`, `max_points`).
Functions of the model's states are evaluated over many states in one mapped call."""

from __future__ import annotations

import threading
from dataclasses import dataclass

import casadi as ca
import numpy as np

from flexmech.models.documents.simulation_spec import SimulateSpec
from flexmech.models.impacts.model import WORKS, ImpactModel
from flexmech.service.impacts.event_driven import EventLayout, rhs_function
from flexmech.service.impacts.kept_rows import reported_rows
from flexmech.service.impacts.stepping import Trace

MAPS_KEPT = 64  # mapped Functions kept (per structure, size and thread)
MAP_COLUMNS = 1 << 15  # states per mapped call at most: a run's stop is looked at between calls
_MAPPED: dict[tuple, ca.Function] = {}
_LOCK = threading.Lock()  # threads share the dictionary, never their CasADi objects


def _energy(model: ImpactModel) -> ca.Function:
    return ca.Function("energy", [model.q, model.v, model.t, model.p], [model.kinetic, model.elastic, model.gravity])


def depth_function(model: ImpactModel) -> ca.Function:
    return ca.Function("depth", [model.q, model.t, model.p], [ca.vertcat(*[pair.indentation for pair in model.pairs])])


def mapped(model: ImpactModel, function, count: int) -> ca.Function:
    """function(model) over `count` states in one call, mapped over a power of two at least
    `count` (so a few maps serve every run of a structure), built once per thread."""
    size = 1 << max(count - 1, 1).bit_length()
    key = (function.__name__, model.structure_key(), size, threading.get_ident())
    with _LOCK:
        fn = _MAPPED.get(key)
    if fn is None:
        fn = function(model).map(size)
        with _LOCK:
            if len(_MAPPED) >= MAPS_KEPT:
                _MAPPED.pop(next(iter(_MAPPED)))
            _MAPPED[key] = fn
    return fn


class RunStopped(Exception):
    """A run's histories were abandoned half-evaluated: its stop() said its job was cancelled
    or ran out of time."""


def evaluated(model: ImpactModel, function, columns: list, p: np.ndarray, stop=None) -> list[np.ndarray]:
    """The outputs of function(model) at every column of `columns` (arrays of shape (rows, count)
    or (count,)), p the same for all: arrays of `count` columns. Evaluated MAP_COLUMNS states
    per call (two million states take seconds), raising RunStopped between calls once stop()."""
    columns = [np.atleast_2d(c) for c in columns]
    count = columns[0].shape[1]
    if count <= MAP_COLUMNS:
        return _evaluated_at_once(model, function, columns, p)
    parts = []
    for start in range(0, count, MAP_COLUMNS):
        if stop is not None and stop():
            raise RunStopped(f"stopped while evaluating states {start} of {count}")
        parts.append(_evaluated_at_once(model, function, [c[:, start : start + MAP_COLUMNS] for c in columns], p))
    return [np.concatenate(outputs, axis=1) for outputs in zip(*parts)]


def _evaluated_at_once(model: ImpactModel, function, columns: list[np.ndarray], p: np.ndarray) -> list[np.ndarray]:
    count = columns[0].shape[1]
    fn = mapped(model, function, count)
    size = fn.size2_in(0)
    padded = [np.pad(c, ((0, 0), (0, size - count)), mode="edge") for c in columns]
    return [np.asarray(out)[:, :count] for out in fn.call([*padded, p])]


@dataclass
class Histories:
    """Every state a run holds (rows), in document units: per coordinate its values, per pair
    its contact quantities, per pin its force; the events and impacts; the rows around events."""

    states: np.ndarray  # SI: [t, q, v, works, ...]
    per: dict[str, float]  # document units per SI unit, by kind
    coordinates: dict[str, np.ndarray]
    velocities: dict[str, np.ndarray]
    pairs: dict[str, dict[str, np.ndarray]]
    joints: dict[str, dict[str, np.ndarray]]
    events: list[dict]
    impacts: list[dict]
    event_rows: np.ndarray

    @property
    def times(self) -> np.ndarray:
        return self.states[:, 0]


def histories(model: ImpactModel, spec: SimulateSpec, trace: Trace, p: np.ndarray, stop=None) -> Histories:
    """Every state's histories and events; stop (looked at between mapped calls) raises RunStopped."""
    states = np.vstack(trace.states)
    n = model.bodies.size
    per = {kind: 1 / model.book.si(1.0, kind, "/units") for kind in ("length", "angle", "force", "energy")}
    if spec.scheme == "moreau":
        pairs, events, impacts, joints, event_rows = _moreau_pairs(model, spec, np.vstack(trace.extras), states, per)
    else:
        pairs, events, impacts, joints, event_rows = _event_pairs(model, states, p, per, stop)
    coordinates, velocities = {}, {}
    for k, name in enumerate(model.coordinate_names()):
        scale = per["angle"] if name.endswith(".theta") else per["length"]
        coordinates[name], velocities[name] = states[:, 1 + k] * scale, states[:, 1 + n + k] * scale
    return Histories(states, per, coordinates, velocities, pairs, joints, events, impacts, event_rows)


def report(
    model: ImpactModel,
    spec: SimulateSpec,
    trace: Trace,
    p: np.ndarray,
    max_kept: int | None = None,
    full: Histories | None = None,
) -> dict:
    """The report of a run. Contact events, impacts and their peak forces come from every
    state of the trace; the histories (and the energies, evaluated on them alone) from the
    kept rows: at most `max_points` spread over the run, with the rows around each event."""
    full = full if full is not None else histories(model, spec, trace, p)
    states, per, book = full.states, full.per, model.book
    limit = spec.max_points if max_kept is None else min(spec.max_points, max_kept)
    keep, stride = reported_rows(len(states), spec.every, limit, full.event_rows)
    if stride > spec.every:
        trace.message = (trace.message + "; " if trace.message else "") + (
            f"kept one state in {stride} of {len(states) - 1} steps, and those around each contact event "
            f"({len(keep)} states; max_points {limit})"
        )
    kept = states[keep]
    energies, balance_error = _energies(model, kept, p)
    units = report_units(book.document.units)
    return {
        "analysis": "simulate",
        "name": book.document.name,
        "scheme": {"name": spec.scheme},
        "status": trace.status,
        "message": trace.message or f"reached t = {states[-1, 0]:g} s",
        "time_reached": float(states[-1, 0]),
        "steps": trace.steps if trace.steps is not None else len(states) - 1,
        "trial_steps": trace.calls,
        "seconds": trace.seconds,
        "step": spec.step,
        "tolerance": spec.tolerance if spec.scheme != "moreau" else None,
        "times": kept[:, 0].tolist(),
        "coordinates": {k: c[keep].tolist() for k, c in full.coordinates.items()},
        "velocities": {k: c[keep].tolist() for k, c in full.velocities.items()},
        "contacts": {
            name: {k: np.asarray(x)[keep].tolist() for k, x in values.items()} for name, values in full.pairs.items()
        },
        "joints": {name: {k: x[keep].tolist() for k, x in values.items()} for name, values in full.joints.items()},
        "events": full.events,
        "impacts": full.impacts,
        "energies": {k: (np.asarray(x) * per["energy"]).tolist() for k, x in energies.items()},
        "energy_balance_error": balance_error,
        "flexure_stiffness": "turning" if model.turning else "constant",
        "clearance": _clearance(model) * per["length"],
        "units": units,
        "series_units": _series_units(full, units),
        "event_units": {name: units[kind] for name, kind in EVENT_FIELDS.items()},
    }


def report_units(document_units) -> dict[str, str]:
    """The unit of each kind of quantity a report holds, in the document's units."""
    length, force, angle = document_units.length, document_units.force, document_units.angle
    return {
        "time": "s",
        "length": length,
        "angle": angle,
        "force": force,
        "moment": f"{force}*{length}",
        "energy": f"{force}*{length}",
        "impulse": f"{force}*s",
        "speed": f"{length}/s",
        "angular_speed": f"{angle}/s",
        "ratio": "1",
        "flag": "0/1",
    }


# The quantity of each field of a contact pair's, a joint's, an impact's or an event's record.
PAIR_FIELDS = {
    "normal_force": "force",
    "friction_force": "force",
    "normal_impulse": "impulse",
    "friction_impulse": "impulse",
    "indentation": "length",
    "slip_speed": "speed",
    "in_contact": "flag",
    "active": "flag",
}
JOINT_FIELDS = {"Fx": "force", "Fy": "force", "N": "force", "M": "moment"}
EVENT_FIELDS = {
    "time": "time",
    "impact_speed": "speed",
    "exit_speed": "speed",
    "duration": "time",
    "rebound_ratio": "ratio",
    "peak_force": "force",
    "impulse": "impulse",
}


def _series_units(full: Histories, units: dict) -> dict:
    """The unit of every series of the report, by the name it is plotted under: a coordinate
    and its velocity (`hinge.x`, `hinge.x.velocity`), a pair's (`conjugate.normal_force`) and a
    joint's fields (`pin.Fx`)."""
    named = {}
    for name in full.coordinates:
        angle = name.endswith(".theta")
        named[name] = units["angle" if angle else "length"]
        named[f"{name}.velocity"] = units["angular_speed" if angle else "speed"]
    for group, fields in ((full.pairs, PAIR_FIELDS), (full.joints, JOINT_FIELDS)):
        for owner, values in group.items():
            named.update({f"{owner}.{field}": units[fields[field]] for field in values if field in fields})
    return named


def _energies(model: ImpactModel, kept: np.ndarray, p: np.ndarray) -> tuple[dict, float]:
    """At the kept states (SI): the energies, the works and their balance (its change from the
    first state), and the balance's largest change relative to the largest energy or work."""
    n = model.bodies.size
    q, v = kept[:, 1 : 1 + n], kept[:, 1 + n : 1 + 2 * n]
    works = kept[:, 1 + 2 * n : 1 + 2 * n + len(WORKS)]
    T, elastic, gravity = (x.ravel() for x in evaluated(model, _energy, [q.T, v.T, kept[:, 0]], p))
    balance = T + elastic + gravity - works.sum(axis=1)
    balance = balance - balance[0]
    size = max(float(np.abs(T).max()), float(np.ptp(elastic + gravity)), float(np.abs(works).max()), 1e-300)
    energies = {
        "kinetic": T,
        "elastic": elastic,
        "gravity": gravity,
        **{name: works[:, k] for k, name in enumerate(WORKS)},
        "balance": balance,
    }
    return energies, float(np.abs(balance).max() / size)


def _clearance(model: ImpactModel) -> float:
    """The radial clearance of the first pin-in-hole pair (SI; 0 without one), for drawing."""
    contacts = model.book.document.contacts
    for pair in contacts.pairs.values():
        pin, other = contacts.sites[pair.site], contacts.objects[pair.object]
        if other.type == "hole":
            return model.book.si(other.radius, "length", "") - model.book.si(pin.radius, "length", "")
    return 0.0


def _event_pairs(model: ImpactModel, states: np.ndarray, p: np.ndarray, per: dict, stop=None):
    n, P = model.bodies.size, len(model.pairs)
    L = EventLayout(n, P)
    cols = [states[:, L.at(k)].T for k in ("contact", "beyond_v0", "beyond_v1", "speed")]
    _, _, F_N, F_T, rate, v_T, pins = evaluated(
        model, rhs_function, [states[:, 1 : 1 + n].T, states[:, 1 + n : 1 + 2 * n].T, states[:, 0], *cols], p, stop
    )
    pen = evaluated(model, depth_function, [states[:, 1 : 1 + n].T, states[:, 0]], p, stop)[0]
    pairs, events, impacts = {}, [], []
    for k, pair in enumerate(model.pairs):
        pairs[pair.name] = {
            "normal_force": F_N[k] * per["force"],
            "friction_force": F_T[k] * per["force"],
            "indentation": pen[k] * per["length"],
            "slip_speed": v_T[k] * per["length"],
            "in_contact": states[:, L.at("contact")][:, k],
        }
    joints = _joints(model, pins.reshape(-1, len(states)).T, per)
    flags = np.column_stack([states[:, L.at(key)] for key in ("contact", "beyond_v0", "beyond_v1")])
    onsets: dict[str, tuple[float, float, int]] = {}  # per pair, its contact's start, impact speed and row
    event_rows = np.nonzero(states[:, L.at("event")] > 0.5)[0]
    for row in event_rows:
        changed = np.nonzero(flags[row] != flags[row - 1])[0] if row else []
        for index in changed:
            kind, k = divmod(index, P)
            name, t = model.pairs[k].name, float(states[row, 0])
            if kind == 0 and flags[row, index] > 0.5:
                onsets[name] = (t, float(rate[k, row]), row)
                events.append(
                    {"time": t, "pair": name, "kind": "contact", "impact_speed": onsets[name][1] * per["length"]}
                )
            elif kind == 0:
                exit_speed = float(-rate[k, row])
                events.append({"time": t, "pair": name, "kind": "separation", "exit_speed": exit_speed * per["length"]})
                if name in onsets:
                    start, speed, first = onsets.pop(name)
                    impacts.append(
                        {
                            "pair": name,
                            "time": start,
                            "impact_speed": speed * per["length"],
                            "exit_speed": exit_speed * per["length"],
                            "duration": t - start,
                            "rebound_ratio": exit_speed / speed,
                            "peak_force": float(F_N[k, first : row + 1].max()) * per["force"],
                        }
                    )
            else:
                level = "v0" if kind == 1 else "v1"
                rising = flags[row, index] > 0.5
                events.append({"time": t, "pair": name, "kind": f"slip {'above' if rising else 'below'} {level}"})
    return pairs, events, impacts, joints, np.unique(np.r_[event_rows - 1, event_rows].clip(0))


def _joints(model: ImpactModel, forces: np.ndarray, per: dict) -> dict:
    """Per joint, what it applies to its `to` body (rows: states; `forces` SI): a pin's force
    (Fx, Fy), a slider's force along the axis normal and couple (N, M)."""
    scale = {"force": per["force"], "moment": per["force"] * per["length"]}
    return {
        name: {label: forces[:, 2 * k + i] * scale[kind] for i, (label, kind) in enumerate(labels)}
        for k, (name, labels) in enumerate(zip(model.joint_names, model.joint_labels))
    }


def _moreau_pairs(model: ImpactModel, spec: SimulateSpec, extras: np.ndarray, states: np.ndarray, per: dict):
    """Per pair its impulses (and the mean forces over their steps), and from every step: the
    contact episodes (consecutive steps with a normal impulse) as onset and separation events,
    and the impacts (an impulse on an approaching contact) with their episode's length and
    peak force. Row k of `extras` is the step from state k - 1 to state k."""
    P, h = len(model.pairs), spec.step
    pairs, events, impacts, rows = {}, [], [], []
    impulse = per["force"]  # N s per document force s
    for k, pair in enumerate(model.pairs):
        lam_N, lam_T = extras[:, k], extras[:, P + k]
        before, after, active = extras[:, 2 * P + k], extras[:, 3 * P + k], extras[:, 4 * P + k]
        pairs[pair.name] = {
            "normal_impulse": lam_N * impulse,
            "friction_impulse": lam_T * impulse,
            "normal_force": lam_N / h * per["force"],
            "friction_force": lam_T / h * per["force"],
            "active": active,
        }
        pushing = np.r_[0, (lam_N > 0).astype(np.int8), 0]
        firsts, lasts = np.nonzero(np.diff(pushing) == 1)[0], np.nonzero(np.diff(pushing) == -1)[0] - 1
        episode = np.zeros(len(lam_N), dtype=int)  # each step's episode (0: none)
        for number, (first, last) in enumerate(zip(firsts, lasts), start=1):
            episode[first : last + 1] = number
            events.append(
                {
                    "time": float(states[first - 1, 0]),
                    "pair": pair.name,
                    "kind": "contact",
                    "impact_speed": float(-before[first]) * per["length"],
                }
            )
            events.append(
                {
                    "time": float(states[last, 0]),
                    "pair": pair.name,
                    "kind": "separation",
                    "exit_speed": float(after[last]) * per["length"],
                    "peak_force": float(lam_N[first : last + 1].max()) / h * per["force"],
                }
            )
            rows += [first - 1, first, last, min(last + 1, len(lam_N) - 1)]
        hits = np.nonzero((lam_N > 0) & (before < 0))[0]
        for row in hits:  # an impact: an impulse on an approaching contact
            if row and lam_N[row - 1] > 0 and before[row - 1] < 0:
                continue  # the same impact, spread over consecutive steps
            first, last = firsts[episode[row] - 1], lasts[episode[row] - 1]
            impacts.append(
                {
                    "pair": pair.name,
                    "time": float(states[row - 1, 0]) if row else 0.0,
                    "impact_speed": float(-before[row]) * per["length"],
                    "exit_speed": float(after[row]) * per["length"],
                    "impulse": float(lam_N[row]) * impulse,
                    "rebound_ratio": float(-after[row] / before[row]),
                    "duration": float(states[last, 0] - states[first - 1, 0]),
                    "peak_force": float(lam_N[first : last + 1].max()) / h * per["force"],
                }
            )
    events.sort(key=lambda event: event["time"])
    return pairs, events, impacts, _joints(model, extras[:, 5 * P :] / h, per), np.asarray(rows, dtype=int)
