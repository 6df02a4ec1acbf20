"""One export: the C library of a mechanism's solver written into a folder (kernels, driver,
header, examples, build files, loader, manifest.json), and as a .tar.gz archive.

Writing is code generation only (no compiler runs here): the caller's build compiles it.
The manifest's worst-case iteration counts are measured at export by the Python twin of the C
iteration (service.export.kernels.iterate) over the example's sweep, warm and cold.
"""

from __future__ import annotations

import io
import json
import tarfile
import time
from dataclasses import asdict
from pathlib import Path

import casadi as ca
import numpy as np

from models import Mechanism, MechanismDocument, compile_mechanism
from service.export.kernels import ExportFunctions, export_functions, iterate
from service.export.plan import ExportOptions, ExportPlan, export_plan
from service.export.sources import Sweep, template_values, write_kernels, write_sources
from service.units import coordinate_kinds

STATUS_CODES = {
    "OK": 0,
    "NOT_CONVERGED": 1,
    "BAD_INPUT": 2,
    "OUT_OF_RANGE": 3,
    "NOT_FINITE": 4,
    "NO_TARGET": 5,
}


def parameters_at(mech: Mechanism, plan: ExportPlan, values: np.ndarray) -> np.ndarray:
    """The nondimensional p with the inputs set to values (document units)."""
    p = mech.p()
    for item, value in zip(plan.inputs, values):
        p[item.slot] = value * item.nd_per_unit
    return p


def _sweep(mech: Mechanism, plan: ExportPlan, functions: ExportFunctions) -> Sweep:
    """The document's sweep when it moves an exported input (to its target when it has one),
    else the first input from zero to its document value."""
    spec = mech.document.sweep
    pointers = [i.pointer for i in plan.inputs]
    if spec is not None and spec.path in pointers:
        index = pointers.index(spec.path)
        start = mech.checked_si(spec.path, spec.start, "/sweep/start", own_checks=False) / mech.doc_factor(
            plan.inputs[index].kind
        )
        if plan.target is not None and plan.target.input == index:
            stop = target_twin(
                mech, plan, functions, np.array([i.default for i in plan.inputs]), plan.target.default_goal
            )
            if stop is not None:
                return Sweep(index, start, stop)
        if spec.stop is not None:
            stop = mech.checked_si(spec.path, spec.stop, "/sweep/stop", own_checks=False) / mech.doc_factor(
                plan.inputs[index].kind
            )
            return Sweep(index, start, stop)
    default = plan.inputs[0].default
    return Sweep(0, 0.0 if default != 0 else -1.0, default if default != 0 else 1.0)


def target_twin(mech: Mechanism, plan: ExportPlan, functions: ExportFunctions, inputs: np.ndarray, goal: float):
    """The target task as the C library runs it from a cold start: the solved input (document
    units) and the Newton steps, or None when it does not converge."""
    found = target_iterations(mech, plan, functions, inputs, goal)
    return None if found is None else found[0]


def target_iterations(mech, plan, functions, inputs, goal):
    p = parameters_at(mech, plan, inputs)
    first = iterate(functions.eq_step, np.zeros(mech.n_free), (p,), plan)
    if first.status != 0:
        return None
    k = plan.target.input
    x0 = np.concatenate([first.x, [p[plan.inputs[k].slot]]])
    found = iterate(functions.target_step, x0, (p, goal), plan)
    if found.status != 0:
        return None
    return found.x[-1] / plan.inputs[k].nd_per_unit, first.iterations + found.iterations


def worst_iterations(mech: Mechanism, plan: ExportPlan, functions: ExportFunctions, sweep: Sweep) -> dict:
    """Newton steps of the twin over the sweep: warm (each point from the previous), cold
    (each from undeformed), and the target's cold start."""
    values = np.array([i.default for i in plan.inputs], dtype=float)
    warm, cold, failed = [], [], 0
    z = np.zeros(mech.n_free)
    for v in np.linspace(sweep.start, sweep.stop, sweep.points):
        values[sweep.index] = v
        p = parameters_at(mech, plan, values)
        a = iterate(functions.eq_step, z, (p,), plan)
        b = iterate(functions.eq_step, np.zeros(mech.n_free), (p,), plan)
        failed += (a.status != 0) + (b.status != 0)
        z = a.x if a.status == 0 else z
        warm.append(a.iterations)
        cold.append(b.iterations)
    out = {
        "measured_over": f"{sweep.points} points of {plan.inputs[sweep.index].c_name} from {sweep.start:.10g} to {sweep.stop:.10g} {plan.inputs[sweep.index].unit}",
        "equilibrium_warm": int(max(warm)),
        "equilibrium_cold": int(max(cold)),
        "failed_points": int(failed),
    }
    if plan.target is not None:
        found = target_iterations(
            mech, plan, functions, np.array([i.default for i in plan.inputs]), plan.target.default_goal
        )
        out["target_cold"] = None if found is None else int(found[1])
    return out


def _coordinates(mech: Mechanism) -> list[dict]:
    rows, cols = coordinate_kinds(mech)
    return [
        {"name": name, "unit": mech.doc_unit(c), "force_unit": mech.doc_unit(r)}
        for name, r, c in zip(mech.free_coordinates, rows, cols)
    ]


def manifest_of(mech, plan: ExportPlan, functions: ExportFunctions, sweep: Sweep, meta: dict, iterations: dict) -> dict:
    target = plan.target
    return {
        "name": plan.name,
        "title": meta["title"],
        "flexmech": meta["version"],
        "casadi": ca.__version__,
        "model": plan.model,
        "header": f"{plan.name}.h",
        "tasks": ["equilibrium", "stiffness", "target"] if target else ["equilibrium", "stiffness"],
        "inputs": [
            {
                "name": i.c_name,
                "pointer": i.pointer,
                "unit": i.unit,
                "default": i.default,
                "low": i.low if np.isfinite(i.low) else None,
                "high": i.high if np.isfinite(i.high) else None,
                "low_excluded": i.low_excluded,
            }
            for i in plan.inputs
        ],
        "outputs": [{"name": o.c_name, "output": o.name, "unit": o.unit} for o in plan.outputs],
        "stiffness": {
            "coordinates": _coordinates(mech),
            "layout": "row-major, rows: generalized forces, columns: coordinates",
        },
        "target": None
        if target is None
        else {
            "output": target.output.name,
            "unit": target.output.unit,
            "goal": target.default_goal,
            "input": plan.inputs[target.input].c_name,
        },
        "status_codes": STATUS_CODES,
        "limits": {
            "max_iterations": plan.options.max_iterations,
            "tolerance": plan.options.tolerance,
            "line_search_halvings": plan.options.line_search_halvings,
            "kernel_calls_per_call_at_most": 1 + plan.options.max_iterations * (plan.options.line_search_halvings + 1),
        },
        "worst_case_iterations": iterations,
        "unknowns": mech.n_free,
        "example_sweep": asdict(sweep) | {"input": plan.inputs[sweep.index].c_name},
    }


def export_document(
    document: MechanismDocument, folder: Path, model: str | None = None, options: ExportOptions = ExportOptions()
) -> dict:
    """export_library of `document` with its curved beams as `model` (default: its own)."""
    return export_library(compile_mechanism(document, model), folder, model or "as in the document", options)


def export_library(mech: Mechanism, folder: Path, model: str, options: ExportOptions = ExportOptions()) -> dict:
    """Write the C library of `mech` (its curved beams' model named by `model`) into folder;
    returns the manifest (also written as manifest.json)."""
    started = time.perf_counter()
    document = mech.document
    plan = export_plan(mech, model, options)
    functions = export_functions(mech, plan)
    sweep = _sweep(mech, plan, functions)
    meta = {"title": document.name or plan.name, "version": _version()}
    iterations = worst_iterations(mech, plan, functions, sweep)
    folder.mkdir(parents=True, exist_ok=True)
    write_kernels(functions, plan.name, folder)
    values = template_values(plan, functions, mech.p(), _coordinates(mech), sweep, meta)
    write_sources(plan, values, folder)
    manifest = manifest_of(mech, plan, functions, sweep, meta, iterations)
    manifest["export_seconds"] = round(time.perf_counter() - started, 3)
    (folder / "manifest.json").write_text(json.dumps(manifest, indent=2) + "\n")
    return manifest


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("flexmech")
    except PackageNotFoundError:
        return "unknown"


def archive(folder: Path) -> bytes:
    """The folder as a .tar.gz, its files under <folder name>/."""
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as tar:
        for path in sorted(folder.iterdir()):
            if path.is_file():
                tar.add(path, arcname=f"{folder.name}/{path.name}")
    return buffer.getvalue()
