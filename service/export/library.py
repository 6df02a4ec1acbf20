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
from pathlib import Path

import casadi as ca
import numpy as np

from flexmech.models import Mechanism, MechanismDocument, compile_mechanism
from flexmech.service.export.kernels import ExportFunctions, export_functions
from flexmech.service.export.measure import example_path, worst_iterations
from flexmech.service.export.plan import ExportOptions, ExportPlan, export_plan
from flexmech.service.export.sources import ExamplePath, template_values, write_kernels, write_sources
from flexmech.service.solvers.equilibrium import check_constrained
from flexmech.service.units import coordinate_kinds

STATUS_CODES = {
    "OK": 0,
    "NOT_CONVERGED": 1,
    "BAD_INPUT": 2,
    "OUT_OF_RANGE": 3,
    "NOT_FINITE": 4,
    "NO_TARGET": 5,
    "NO_CONTACT": 6,
}


def _coordinates(mech: Mechanism) -> list[dict]:
    rows, cols = coordinate_kinds(mech)
    return [
        {"name": name, "unit": mech.doc_unit(c), "force_unit": mech.doc_unit(r)}
        for name, r, c in zip(mech.free_coordinates, rows, cols)
    ]


def _path(plan: ExportPlan, path: ExamplePath) -> dict:
    return {
        "task": path.task,
        "points": path.points,
        "inputs": [
            {"name": plan.inputs[k].c_name, "start": a, "stop": b, "unit": plan.inputs[k].unit}
            for k, a, b in zip(path.indices, path.starts, path.stops)
        ],
    }


def _contact(functions: ExportFunctions) -> dict | None:
    if functions.contact is None:
        return {"note": functions.contact_note} if functions.contact_note else None
    return {
        "outputs": [{"output": n, "unit": u} for n, u in zip(functions.contact.names, functions.contact.units)],
        "unknowns": functions.contact.n_v,
        "model": "frictionless; complementarity in Fischer-Burmeister form; forces are the multipliers",
    }


def manifest_of(
    mech, plan: ExportPlan, functions: ExportFunctions, path: ExamplePath, meta: dict, iterations: dict
) -> dict:
    target = plan.target
    tasks = ["equilibrium", "stiffness"] + (["target"] if target else []) + (["contact"] if functions.contact else [])
    return {
        "name": plan.name,
        "title": meta["title"],
        "flexmech": meta["version"],
        "casadi": ca.__version__,
        "model": plan.model,
        "header": f"{plan.name}.h",
        "tasks": tasks,
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
        "contact": _contact(functions),
        "status_codes": STATUS_CODES,
        "limits": {
            "max_iterations": plan.options.max_iterations,
            "tolerance": plan.options.tolerance,
            "line_search_halvings": plan.options.line_search_halvings,
            "kernel_calls_per_call_at_most": 1 + plan.options.max_iterations * (plan.options.line_search_halvings + 1),
        },
        "worst_case_iterations": iterations,
        "unknowns": mech.n_free,
        "example_path": _path(plan, path),
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
    check_constrained(mech)  # a free motion has no static equilibrium: named, as flexmech solve names it
    functions = export_functions(mech, plan)
    path = example_path(mech, plan, functions)
    meta = {"title": document.name or plan.name, "version": _version()}
    iterations = worst_iterations(mech, plan, functions, path)
    folder.mkdir(parents=True, exist_ok=True)
    write_kernels(functions, plan.name, folder)
    values = template_values(plan, functions, mech.p(), _coordinates(mech), path, meta)
    write_sources(plan, values, folder)
    manifest = manifest_of(mech, plan, functions, path, meta, iterations)
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
