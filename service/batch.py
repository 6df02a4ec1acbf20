"""Batch runs for containers: every mechanism document in a folder solved (or swept, when it
declares a sweep), one result file per document and a summary. One document failing does not
stop the others."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path

from models import MechanismError, compile_mechanism, load_document
from service.analyses.equilibrium import equilibrium_report
from service.reports import plain
from service.equilibrium import NewtonOptions
from service.sweep import document_sweep

DOCUMENT_SUFFIXES = (".json", ".yaml", ".yml")


def batch_documents(directory: Path) -> list[Path]:
    return sorted(p for p in directory.iterdir() if p.is_file() and p.suffix.lower() in DOCUMENT_SUFFIXES)


def run_document(path: Path, options: NewtonOptions) -> dict:
    """The result of one document: its sweep when it declares one, else its equilibrium.
    Carries `status` (converged, not_converged, singular, time_limit or error)."""
    started = time.perf_counter()
    try:
        mech = compile_mechanism(load_document(path))
        if mech.document.sweep is not None:
            result, target = document_sweep(mech, options)
            payload = {"analysis": "sweep", "name": mech.document.name}
            if target is not None:
                payload["target"] = {"status": target.status, "value": target.value,
                                     "unit": mech.doc_unit(mech.parameter_kind(mech.document.sweep.path))}
            if result is None:
                payload.update(status=target.status, message="the sweep's target was not reached")
            else:
                failed = [s for s in result.status if s != "converged"]
                payload.update(status="converged" if not failed else "not_converged",
                               message=f"{len(failed)} of {len(result.status)} points did not converge" if failed else "",
                               sweep=result.to_dict())
        else:
            payload = equilibrium_report(mech, options)
    except MechanismError as exc:
        payload = {"analysis": None, "status": "error", "message": str(exc)}
    payload["seconds"] = time.perf_counter() - started
    return plain(payload)


def run_batch(directory: Path, out: Path, options: NewtonOptions = NewtonOptions(),
              progress: Callable[[Path, dict], None] | None = None) -> dict:
    """Write out/<document stem>.json for each document and out/summary.json; return the summary."""
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for path in batch_documents(directory):
        payload = run_document(path, options)
        result_file = out / f"{path.stem}.json"
        result_file.write_text(json.dumps({"document": path.name, **payload}, indent=2))
        rows.append({"document": path.name, "result": result_file.name, "analysis": payload.get("analysis"),
                     "status": payload["status"], "message": payload.get("message", ""),
                     "seconds": payload["seconds"]})
        if progress is not None:
            progress(path, payload)
    summary = {"directory": str(directory), "documents": len(rows),
               "succeeded": sum(r["status"] == "converged" for r in rows),
               "failed": sum(r["status"] != "converged" for r in rows), "results": rows}
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    return summary
