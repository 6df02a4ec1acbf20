"""Single analyses as plain data: what /v1/solve answers and what `flexmech batch` writes.

Each function takes a mechanism document (a parsed JSON object) and returns a JSON-able dict
in the document's units. Every problem with the input raises MechanismError whose pointer is
relative to the request (the document's fields under /document), so the HTTP layer and the
CLI report the same field.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from models import Mechanism, MechanismError, compile_mechanism
from models.document import parse_document
from models import MODELS
from service.equilibrium import NewtonOptions, solve_equilibrium
from service.inverse import inverse_wrenches
from service.stiffness import tangent_stiffness
from service.sweep import solve_for_target


@dataclass(frozen=True)
class Limits:
    max_elements: int = 200
    max_sweep_points: int = 20_000
    solve_time_limit: float | None = 10.0


def escape_pointer_part(part: str) -> str:
    return str(part).replace("~", "~0").replace("/", "~1")


def under(prefix: str, exc: MechanismError) -> MechanismError:
    """The same error, its pointer placed under `prefix` (e.g. /document)."""
    return MechanismError(prefix + exc.pointer, exc.problem)


def plain(obj: Any) -> Any:
    """JSON-able copy: numpy scalars and arrays to Python numbers and lists, non-finite to None."""
    if isinstance(obj, dict):
        return {str(k): plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return plain(obj.tolist())
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        value = float(obj)
        return value if math.isfinite(value) else None
    return obj


def newton_options(options: dict | None, time_limit: float | None = None, pointer: str = "/options") -> NewtonOptions:
    """NewtonOptions from a request's options object; unknown or bad options name the field.
    The service's time limit caps any time limit asked for."""
    options = dict(options or {})
    known = {f.name for f in fields(NewtonOptions)}
    for name in options:
        if name not in known:
            raise MechanismError(f"{pointer}/{escape_pointer_part(name)}",
                                 f"unknown option (options: {', '.join(sorted(known))})")
    asked = options.get("time_limit")
    if time_limit is not None:
        options["time_limit"] = time_limit if asked is None else min(float(asked), time_limit)
    try:
        return NewtonOptions(**options)
    except (TypeError, ValueError) as exc:
        name = str(exc).split(":", 1)[0] if ":" in str(exc) else ""
        field = f"{pointer}/{name}" if name in known else pointer
        raise MechanismError(field, str(exc).split(": ", 1)[-1]) from None


def compile_request(document: dict, model: str | None = None, overrides: dict[str, Any] | None = None,
                    limits: Limits = Limits()) -> Mechanism:
    """Validate and compile a request's document, with its model choice and overrides."""
    try:
        doc = parse_document(document)
    except MechanismError as exc:
        raise under("/document", exc) from None
    if len(doc.elements) > limits.max_elements:
        raise MechanismError("/document/elements", f"{len(doc.elements)} elements: the limit is {limits.max_elements}")
    if model is not None and model not in MODELS:
        raise MechanismError("/model", f"unknown model '{model}' ({', '.join(MODELS)})")
    try:
        mech = compile_mechanism(doc, model)
    except MechanismError as exc:
        raise under("/document", exc) from None
    for pointer, value in (overrides or {}).items():
        try:
            mech = mech.with_values({pointer: value})
        except MechanismError as exc:
            raise MechanismError(f"/overrides/{escape_pointer_part(pointer)}", exc.problem) from None
    return mech


def equilibrium_report(mech: Mechanism, options: NewtonOptions, stiffness: bool = False,
                       target: dict | None = None, sensitivities: dict | None = None) -> dict:
    """Solve the equilibrium; status, diagnostics, displacements and outputs in document units.

    target = {path, output, equals}: instead of the document's value of the numeric field
    `path`, find the value for which `output` equals `equals` (document units), e.g. the
    actuation force that closes a gripper; reported under "target".
    sensitivities = {parameters, outputs}: d(outputs)/d(parameters) at the solution (the
    target's field following), reported under "sensitivities"."""
    found = None
    try:
        if target is None:
            result = solve_equilibrium(mech, options)
        else:
            try:
                mech.parameter_index(target["path"])
            except MechanismError as exc:
                raise MechanismError("/target/path", exc.problem) from None
            if target["output"] not in mech.graphs.output_names:
                raise MechanismError("/target/output", f"unknown output '{target['output']}'")
            found = solve_for_target(mech, target["path"], target["output"], float(target["equals"]), options)
            result = found.equilibrium
            mech = result.mechanism
    except MechanismError as exc:
        raise (exc if exc.pointer.startswith("/target") else under("/document", exc)) from None
    report = {"analysis": "equilibrium", "name": mech.document.name, **result.summary(),
              "history": result.history, "output_units": output_units(mech),
              "displacement_units": coordinate_units(mech)}
    if found is not None:
        report["target"] = {"path": target["path"], "value": found.value, "status": found.status,
                            "unit": mech.doc_unit(mech.parameter_kind(target["path"]))}
    if stiffness and result.converged:
        report["stiffness"] = stiffness_dict(mech, result.z)
    if sensitivities is not None and result.converged:
        from service.sensitivity import equilibrium_sensitivities

        try:
            found_target = (target["path"], target["output"]) if target is not None else None
            report["sensitivities"] = equilibrium_sensitivities(
                mech, result.z, sensitivities["parameters"], sensitivities["outputs"], found_target).to_dict()
        except MechanismError as exc:
            raise MechanismError("/sensitivities" + exc.pointer, exc.problem) from None
    return plain(report)


def linearization_report(mech: Mechanism, options: NewtonOptions, at: str = "equilibrium") -> dict:
    """K_T and its terms at the equilibrium under the document's loads (or undeformed)."""
    if at not in ("equilibrium", "undeformed"):
        raise MechanismError("/at", f"unknown state '{at}' (equilibrium, undeformed)")
    report: dict[str, Any] = {"analysis": "linearization", "name": mech.document.name, "at": at}
    z = None
    if at == "equilibrium":
        try:
            result = solve_equilibrium(mech, options)
        except MechanismError as exc:
            raise under("/document", exc) from None
        report.update(result.summary())
        if not result.converged:
            return plain(report)
        z = result.z
    else:
        report.update(status="converged", message="", iterations=0)
    report["stiffness"] = stiffness_dict(mech, z)
    return plain(report)


def inverse_report(mech: Mechanism, displacements: dict[str, Any]) -> dict:
    """The wrench each body needs (loads plus supports) to hold the given body displacements
    [dx, dy, rotation] in document units; bodies not named stay where they are."""
    wrenches = inverse_wrenches(mech, {k: tuple(v) for k, v in displacements.items()})
    force, moment = mech.doc_unit("force"), mech.doc_unit("moment")
    return plain({
        "analysis": "inverse", "name": mech.document.name, "status": "converged", "message": "",
        "wrenches": {b: {"Fx": w[0], "Fy": w[1], "M": w[2]} for b, w in wrenches.items()},
        "wrench_units": {"Fx": force, "Fy": force, "M": moment},
    })


def stiffness_dict(mech: Mechanism, z) -> dict:
    kt = tangent_stiffness(mech, z)
    return {"coordinates": kt.coordinates, "row_units": kt.row_units, "column_units": kt.column_units,
            "K": kt.K, "terms": kt.terms, "symmetric": kt.symmetric}


def output_units(mech: Mechanism) -> dict[str, str]:
    g = mech.graphs
    return {name: mech.doc_unit(kind) for name, kind in zip(g.output_names, g.output_kinds)}


def coordinate_units(mech: Mechanism) -> dict[str, str]:
    kinds = ("length", "length", "angle")
    return {name: mech.doc_unit(kinds[c]) for name, (_, c) in zip(mech.free_coordinates, mech.structure.free)}


__all__ = ["Limits", "compile_request", "equilibrium_report", "inverse_report", "linearization_report",
           "newton_options", "plain", "under"]
