"""The parametric study of an impact model (seed 004 Sec. 7), with numbers in place of the
paper's arrows: each chosen field of the document is moved by its step, up and down, one at
a time, and every run is compared with the nominal one at every state the nominal run holds
(a Moreau run's every step: an impact lasts one step, which no common sampling grid would
catch). For each field and each compared quantity (a body's x, y, theta; a pair's F_N, F_T)
it reports

  departure   the first time the difference exceeds `tolerance` times the nominal range
              (None: it never does), the paper's "early" versus "gradually amplifying";
  rms         the root-mean-square difference over the run, relative to the nominal range;
  max         the largest difference, relative likewise;

and per pair the run's contacts from its events: how many, the first onset and separation,
and the peak normal force and its time. A run is compared where it is made (each task runs
the nominal one too, once per process), so a stored point holds numbers, not histories.
"""

from __future__ import annotations

import copy
import json
import threading
from collections import OrderedDict
from collections.abc import Sequence
from typing import Protocol

import numpy as np

from flexmech.models import MechanismError
from flexmech.models.documents.document import MechanismDocument
from flexmech.models.documents.simulation_spec import SimulateSpec
from flexmech.service.impacts.run import Histories, run_with_histories


class StudyField(Protocol):
    path: str
    step: float


def study_fields(document: dict, fields: Sequence[StudyField]) -> list[tuple[str, float]]:
    """(pointer, step) per field, each a number of the document."""
    out = []
    for k, item in enumerate(fields):
        pointer, step = item.path, item.step
        where = f"/study/fields/{k}"
        if not pointer.startswith("/"):
            raise MechanismError(
                f"{where}/path", "give the field as a JSON pointer into the document, e.g. /contacts/sites/pin/radius"
            )
        if step == 0:
            raise MechanismError(f"{where}/step", "give a non-zero number: the field moves by +step and -step")
        value = _at(document, pointer, f"{where}/path")
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            raise MechanismError(f"{where}/path", f"{pointer} is not a number of the document (it is {value!r})")
        out.append((pointer, float(step)))
    if not out:
        raise MechanismError("/study/fields", "give at least one field to vary")
    return out


def _at(document: dict, pointer: str, where: str):
    node = document
    for part in pointer[1:].split("/"):
        part = part.replace("~1", "/").replace("~0", "~")
        if isinstance(node, dict) and part in node:
            node = node[part]
        elif isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        else:
            raise MechanismError(where, f"the document has no field {pointer}")
    return node


def with_overrides(document: dict, overrides: dict | None) -> dict:
    """The document with a request's `overrides` (numbers by pointer) written in."""
    doc = document
    for pointer, value in (overrides or {}).items():
        old = _at(doc, pointer, f"/overrides/{pointer.lstrip('/').replace('/', '~1')}")
        if not isinstance(old, (int, float)) or not isinstance(value, (int, float)):
            raise MechanismError(
                f"/overrides/{pointer.lstrip('/').replace('/', '~1')}", "an impact study overrides numbers with numbers"
            )
        doc = variant(doc, pointer, value - old)
    return doc


def variant(document: dict, pointer: str | None, change: float) -> dict:
    """The document with the field at pointer moved by change (None: the nominal one)."""
    if pointer is None:
        return document
    doc = copy.deepcopy(document)
    parts = [p.replace("~1", "/").replace("~0", "~") for p in pointer[1:].split("/")]
    node = doc
    for part in parts[:-1]:
        node = node[int(part)] if isinstance(node, list) else node[part]
    last = int(parts[-1]) if isinstance(node, list) else parts[-1]
    node[last] = node[last] + change
    return doc


NOMINALS_KEPT = 2  # nominal runs kept per process, by document and settings
_NOMINALS: OrderedDict[str, tuple[Histories, dict]] = OrderedDict()
_LOCK = threading.Lock()


def _run(document: dict, simulate: dict | None, stop, max_steps: int) -> tuple[Histories | None, dict]:
    doc = MechanismDocument.model_validate(document)
    base = doc.simulate.model_dump() if doc.simulate is not None else {}
    spec = SimulateSpec.model_validate({**base, **{k: v for k, v in (simulate or {}).items() if v is not None}})
    return run_with_histories(doc, spec, stop=stop, max_steps=max_steps)


def nominal_run(
    document: dict, simulate: dict | None, stop=None, max_steps: int = 2_000_000
) -> tuple[Histories | None, dict]:
    """The study's run of the document as given, kept (a stopped one, without histories, is not)."""
    key = json.dumps([document, simulate], sort_keys=True)
    with _LOCK:
        kept = _NOMINALS.get(key)
    if kept is not None:
        return kept
    full, report = _run(document, simulate, stop, max_steps)
    if full is None:
        return full, report  # stopped, not kept: a later task runs it whole
    with _LOCK:
        if len(_NOMINALS) >= NOMINALS_KEPT:
            _NOMINALS.popitem(last=False)
        _NOMINALS[key] = (full, report)
    return full, report


def study_point(
    document: dict,
    simulate: dict | None,
    pointer: str | None,
    change: float,
    tolerance: float,
    stop=None,
    max_steps: int = 2_000_000,
) -> dict:
    """One run of the study (pointer None: the nominal one) with its contacts and, for a
    moved field, its influence against the nominal run."""
    full, report = (
        nominal_run(document, simulate, stop, max_steps)
        if pointer is None
        else _run(variant(document, pointer, change), simulate, stop, max_steps)
    )
    if full is None:  # stopped (cancelled or out of time): the job keeps no point of it
        return {"status": "stopped", "message": report["message"]}
    point = {
        "status": report["status"],
        "message": report["message"],
        "time_reached": report["time_reached"],
        "seconds": report["seconds"],
        "impacts": len(report["impacts"]),
        "contacts": contact_summary(full),
    }
    if pointer is not None:
        nominal, _ = nominal_run(document, simulate, stop, max_steps)
        if nominal is None:
            point["status"] = "stopped"
        else:
            point["influence"] = compared(nominal, full, tolerance)
    return point


def contact_summary(full: Histories) -> dict:
    """Per pair, from its events and every held state: the contacts, the first onset and
    separation, and the peak normal force with its time."""
    out = {}
    for name, values in full.pairs.items():
        onsets = [e["time"] for e in full.events if e["pair"] == name and e["kind"] == "contact"]
        ends = [e["time"] for e in full.events if e["pair"] == name and e["kind"] == "separation"]
        force = np.asarray(values["normal_force"])
        top = int(np.argmax(force)) if len(force) else 0
        out[name] = {
            "contacts": len(onsets),
            "first_contact": onsets[0] if onsets else None,
            "first_separation": ends[0] if ends else None,
            "peak_force": float(force[top]) if len(force) else 0.0,
            "peak_time": float(full.times[top]) if len(force) and force[top] > 0 else None,
        }
    return out


def _series(full: Histories) -> dict[str, np.ndarray]:
    series = dict(full.coordinates)
    for name, contact in full.pairs.items():
        series[f"{name}.F_N"] = np.asarray(contact["normal_force"])
        series[f"{name}.F_T"] = np.asarray(contact["friction_force"])
    return series


def compared(nominal: Histories, run: Histories, tolerance: float) -> dict:
    """departure, rms and max per compared quantity, at the nominal run's states up to where
    both reached: directly on a common grid (Moreau's fixed steps), else with the run
    interpolated linearly between its own states."""
    times, theirs = nominal.times, run.times
    same = len(times) == len(theirs) and np.array_equal(times, theirs)
    upto = times <= theirs[-1] * (1 + 1e-12)
    reference_series, run_series = _series(nominal), _series(run)
    return {
        name: _measures(
            times[upto],
            reference[upto],
            run_series[name] if same else np.interp(times[upto], theirs, run_series[name]),
            tolerance,
        )
        for name, reference in reference_series.items()
    }


def legacy_influence(nominal: dict, run: dict, until: float, tolerance: float) -> dict:
    """The influence of points stored before runs were compared where they are made: their
    series sampled on a common grid of 2000 times."""
    grid = np.linspace(0.0, until, len(next(iter(nominal["series"].values()))))
    return {
        name: _measures(grid, np.asarray(reference), np.asarray(run["series"][name]), tolerance)
        for name, reference in nominal["series"].items()
    }


def _measures(times: np.ndarray, reference: np.ndarray, values: np.ndarray, tolerance: float) -> dict:
    """departure, rms and max of values against reference, relative to the reference's range."""
    difference = np.abs(values - reference) / max(float(np.ptp(reference)), 1e-300)
    beyond = np.nonzero(difference > tolerance)[0]
    return {
        "departure": float(times[beyond[0]]) if len(beyond) else None,
        "rms": float(np.sqrt(np.mean(difference**2))),
        "max": float(difference.max()),
    }
