"""Batch runs for containers: every mechanism document in a folder run through the analysis it
declares (its `optimize` section, else its `inverse` section, else its `sweep`, else the
equilibrium under its loads), or through one analysis of the registry with its typed options
for all of them, or exported as a C library each (service.export, the export job's fields: its
folder c/<result stem>/ beside the results); one result file per document and a summary.

A document that cannot be read or modelled (not UTF-8, nested too deep, not a mapping, an
invalid field) is one failed row; the others still run and the summary is still written.
Results never go into the input folder itself, and no result overwrites another or the
summary: a document's result is <stem>.json, or <file name>.json when its stem is shared by
another document or is "summary" (a.json, a.yaml -> a.json.json, a.yaml.json)."""

from __future__ import annotations

import json
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from flexmech.models import Mechanism, MechanismDocument, MechanismError, compile_mechanism, load_document
from flexmech.service.analyses import Analysis, AnalysisOptions, AnalysisRequest
from flexmech.service.analyses.equilibrium import equilibrium_report
from flexmech.service.design.optimize import optimize
from flexmech.service.design.problem import design_problem
from flexmech.service.jobs.export import ExportJobOptions, export_options
from flexmech.service.solvers.equilibrium import NewtonOptions
from flexmech.service.solvers.inverse_links import inverse_links
from flexmech.service.solvers.reports import plain
from flexmech.service.solvers.sweep import document_sweep

DOCUMENT_SUFFIXES = (".json", ".yaml", ".yml")
SUMMARY = "summary.json"
# The statuses that count as success, per declared analysis (a registry analysis: converged, or
# a simulation finished); any other status (and "error") is a failure.
SUCCESS = {
    "optimize": ("optimal", "acceptable"),
    "inverse": ("converged",),
    "sweep": ("converged",),
    "equilibrium": ("converged",),
    "export": ("exported",),
}
REGISTRY_SUCCESS = ("converged", "finished")


def succeeded(analysis: str | None, status: str) -> bool:
    """Whether a row of the summary (its analysis and status) is a success."""
    if analysis is None:
        return False
    return status in SUCCESS.get(analysis, REGISTRY_SUCCESS)


def batch_documents(directory: Path) -> list[Path]:
    return sorted(p for p in directory.iterdir() if p.is_file() and p.suffix.lower() in DOCUMENT_SUFFIXES)


def same_folder(directory: Path, out: Path) -> bool:
    """Whether `out` is `directory` by any path (symlinks, '.', '..'), existing or not yet."""
    if out.resolve() == directory.resolve():
        return True
    return out.is_dir() and out.samefile(directory)


def result_names(documents: list[Path]) -> dict[Path, str]:
    """The result file of each document: <stem>.json, or <file name>.json when the stem is
    shared (compared without case), is "summary", or its <stem>.json would still clash."""
    stems = Counter(p.stem.casefold() for p in documents)
    full = {p for p in documents if stems[p.stem.casefold()] > 1 or p.stem.casefold() == "summary"}
    while True:  # ends: `full` only grows, and file names (hence <file name>.json) are distinct
        names = {p: f"{p.name if p in full else p.stem}.json" for p in documents}
        taken = Counter(name.casefold() for name in names.values())
        clashing = {p for p, name in names.items() if taken[name.casefold()] > 1} - full
        if not clashing:
            return names
        full |= clashing


def declared_analysis(document: MechanismDocument) -> str:
    """The analysis a document declares, by precedence: optimize, inverse, sweep, else equilibrium."""
    return next(
        (name for name in ("optimize", "inverse", "sweep") if getattr(document, name) is not None), "equilibrium"
    )


def optimization_report(mech: Mechanism, options: NewtonOptions) -> dict:
    """The design optimization of the `optimize` section (IPOPT; the Newton options are not used)."""
    return optimize(design_problem(mech, mech.document.optimize)).summary()


def inverse_report(mech: Mechanism, options: NewtonOptions) -> dict:
    """The link inverse of the `inverse` section: unknown loads (document units), links, bodies."""
    spec = mech.document.inverse
    result = inverse_links(mech, spec.shapes, spec.internal_forces, spec.unknown_loads, options)
    return {
        "analysis": "inverse",
        "name": mech.document.name,
        "internal_forces": spec.internal_forces,
        **result.__dict__,
        "load_units": {pointer: mech.doc_unit(mech.parameter_kind(pointer)) for pointer in result.loads},
    }


def sweep_report(mech: Mechanism, options: NewtonOptions) -> dict:
    """The sweep of the `sweep` section, with its target when it has one."""
    result, target = document_sweep(mech, options)
    payload = {"analysis": "sweep", "name": mech.document.name}
    if target is not None:
        payload["target"] = {
            "status": target.status,
            "value": target.value,
            "unit": mech.doc_unit(mech.parameter_kind(mech.document.sweep.path)),
        }
    if result is None:
        payload.update(status=target.status, message="the sweep's target was not reached")
    else:
        failed = [s for s in result.status if s != "converged"]
        payload.update(
            status="converged" if not failed else "not_converged",
            message=f"{len(failed)} of {len(result.status)} points did not converge" if failed else "",
            sweep=result.to_dict(),
        )
    return payload


ANALYSES: dict[str, Callable[[Mechanism, NewtonOptions], dict]] = {
    "optimize": optimization_report,
    "inverse": inverse_report,
    "sweep": sweep_report,
    "equilibrium": equilibrium_report,
}


@dataclass(frozen=True)
class Chosen:
    """One analysis of the registry for every document, with its typed options."""

    analysis: Analysis
    options: AnalysisOptions


@dataclass(frozen=True)
class Export:
    """Every document exported as a C library instead of analysed: the export job's own fields
    (service.jobs.export.ExportJobOptions: name, inputs, outputs, ranges, target, ...), each
    library written to <out>/c/<result stem>/."""

    options: ExportJobOptions


LIBRARIES = "c"  # the folder of the exported libraries in the results' folder


def export_report(mech: Mechanism, path: Path, export: Export, folder: Path) -> dict:
    """The document's C library written to `folder` (named after the document's file unless
    the fields name it); its manifest."""
    from flexmech.service.export.library import export_library

    options = export_options(export.options.model_copy(update={"name": export.options.name or path.stem}))
    manifest = export_library(mech, folder, "as in the document", options)
    library = f"{folder.parent.name}/{folder.name}"
    return {"analysis": "export", "status": "exported", "message": "", "library": library, "manifest": manifest}


def run_document(
    path: Path, options: NewtonOptions, chosen: Chosen | Export | None = None, out: Path | None = None
) -> dict:
    """The result of one document, by the analysis it declares (or the one chosen, or its
    export into `out`, the library's folder). Carries `analysis` (None when the document could
    not be read or modelled), `status` (the analysis's own, or error) and `message`."""
    started = time.perf_counter()
    analysis = None
    try:
        mech = compile_mechanism(load_document(path))
        if isinstance(chosen, Export):
            analysis = "export"
            payload = export_report(mech, path, chosen, out or Path(LIBRARIES) / path.stem)
        elif chosen is not None:
            analysis = chosen.analysis.name
            payload = chosen.analysis.run(mech, AnalysisRequest(options, chosen.options))
        else:
            analysis = declared_analysis(mech.document)
            payload = ANALYSES[analysis](mech, options)
    except MechanismError as exc:
        payload = {"analysis": analysis, "status": "error", "message": str(exc)}
    payload["seconds"] = time.perf_counter() - started
    return plain(payload)


def run_batch(
    directory: Path,
    out: Path,
    options: NewtonOptions = NewtonOptions(),
    progress: Callable[[Path, dict], None] | None = None,
    chosen: Chosen | Export | None = None,
) -> dict:
    """Write out/<result name> for each document (see result_names) and out/summary.json;
    return the summary. ValueError if `out` is `directory` (the results would replace it)."""
    if same_folder(directory, out):
        raise ValueError(f"'{out}' is the input folder '{directory}': the results would overwrite its documents")
    out.mkdir(parents=True, exist_ok=True)
    documents = batch_documents(directory)
    names = result_names(documents)
    rows = []
    for path in documents:
        library = out / LIBRARIES / names[path].removesuffix(".json")
        payload = run_document(path, options, chosen, library)
        result_file = out / names[path]
        result_file.write_text(json.dumps({"document": path.name, **payload}, indent=2))
        ok = succeeded(payload.get("analysis"), payload["status"])
        rows.append(
            {
                "document": path.name,
                "result": result_file.name,
                "analysis": payload.get("analysis"),
                "status": payload["status"],
                "succeeded": ok,
                "message": payload.get("message", ""),
                "seconds": payload["seconds"],
            }
        )
        if progress is not None:
            progress(path, payload)
    summary = {
        "directory": str(directory),
        "documents": len(rows),
        "succeeded": sum(r["succeeded"] for r in rows),
        "failed": sum(not r["succeeded"] for r in rows),
        "results": rows,
    }
    (out / SUMMARY).write_text(json.dumps(summary, indent=2))
    return summary
