"""The parametric study of an impact model (seed 004 Sec. 7), with numbers in place of the
paper's arrows: each chosen field of the document is moved by its step, up and down, one at
a time, and every run is compared with the nominal one on a common time grid. For each
field and each compared quantity (a body's x, y, theta; a pair's F_N, F_T) it reports

  departure   the first time the difference exceeds `tolerance` times the nominal range
              (None: it never does), the paper's "early" versus "gradually amplifying";
  rms         the root-mean-square difference over the run, relative to the nominal range;
  max         the largest difference, relative likewise.
"""

from __future__ import annotations

import copy

import numpy as np

from models import MechanismError
from models.document import MechanismDocument
from models.simulation_spec import SimulateSpec
from service.impacts.run import run_impacts

SAMPLES = 2000  # the common time grid


def study_fields(document: dict, fields: list[dict]) -> list[tuple[str, float]]:
    """(pointer, step) per field, each a number of the document."""
    out = []
    for k, item in enumerate(fields):
        pointer, step = item.get("path"), item.get("step")
        where = f"/study/fields/{k}"
        if not isinstance(pointer, str) or not pointer.startswith("/"):
            raise MechanismError(f"{where}/path", "give the field as a JSON pointer into the document, e.g. "
                                 "/impacts/surfaces/pin/radius")
        if not isinstance(step, (int, float)) or isinstance(step, bool) or step == 0:
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
            raise MechanismError(f"/overrides/{pointer.lstrip('/').replace('/', '~1')}", "an impact study overrides "
                                 "numbers with numbers")
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


def sampled_run(document: dict, simulate: dict | None, stop=None, max_steps: int = 2_000_000) -> dict:
    """One run's compared quantities on the common grid (document units)."""
    doc = MechanismDocument.model_validate(document)
    base = doc.simulate.model_dump() if doc.simulate is not None else {}
    spec = SimulateSpec.model_validate({**base, **{k: v for k, v in (simulate or {}).items() if v is not None}})
    _, report = run_impacts(doc, spec, stop=stop, max_steps=max_steps)
    grid = np.linspace(0.0, spec.until, SAMPLES)
    times = np.asarray(report["times"])
    series = dict(report["coordinates"])
    for name, contact in report["contacts"].items():
        series[f"{name}.F_N"] = contact["normal_force"]
        series[f"{name}.F_T"] = contact["friction_force"]
    return {"status": report["status"], "message": report["message"], "time_reached": report["time_reached"], "seconds": report["seconds"],
            "impacts": len(report["impacts"]),
            "series": {name: np.interp(grid, times, values).tolist() for name, values in series.items()}}


def influence(nominal: dict, run: dict, until: float, tolerance: float) -> dict:
    """departure, rms and max per compared quantity of a run against the nominal one."""
    grid = np.linspace(0.0, until, SAMPLES)
    out = {}
    for name, reference in nominal["series"].items():
        reference, values = np.asarray(reference), np.asarray(run["series"][name])
        span = max(float(np.ptp(reference)), 1e-300)
        difference = np.abs(values - reference) / span
        beyond = np.nonzero(difference > tolerance)[0]
        out[name] = {"departure": float(grid[beyond[0]]) if len(beyond) else None,
                     "rms": float(np.sqrt(np.mean(difference**2))), "max": float(difference.max())}
    return out
