"""`flexmech build`: compile the kernels a document runs on (or every example's), then its
window of time steps that calls them (service.kernels.windows), in the foreground, each compiler run under the build limits; a table of what was built: the C's size,
the compile time and the compiler's peak memory. Later runs, and a server on the same cache,
use them; a server also builds them itself, in its build queue, when first asked."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flexmech.api.cli.application import app
from flexmech.api.cli.common import EXIT_NOT_CONVERGED, OptionError, consoles, shown, table_of, user_errors, write_json
from flexmech.api.cli.options import JsonOpt, document_argument, mechanism


@app.command()
def build(
    documents: Annotated[
        list[Path] | None,
        typer.Argument(help="Mechanism documents, or examples' names.", show_default=False, parser=document_argument),
    ] = None,
    examples: Annotated[bool, typer.Option("--examples", help="Every shipped example.")] = False,
    seconds: Annotated[float, typer.Option("--seconds", help="Time limit of one compiler run (s).")] = 60.0,
    memory: Annotated[float, typer.Option("--memory", help="Memory limit of one compiler run (MiB).")] = 1024.0,
    json_out: JsonOpt = None,
) -> None:
    """Compile the kernels documents run on, once per kernel (shared by every document using it), and then each
    document's window of time steps that calls them."""
    from flexmech.service.examples import examples_directory
    from flexmech.service.kernels.build import BuildLimits, Compiler
    from flexmech.service.kernels.needs import builds_of, window_builds

    out, err = consoles()
    with user_errors(err):
        paths = list(documents or [])
        if examples:
            directory = examples_directory()
            if directory is None:
                raise OptionError(
                    "--examples", "the package's examples are missing (a broken install: reinstall flexmech)"
                )
            paths += sorted(directory.glob("*.json"))
        if not paths:
            raise OptionError("DOCUMENTS", "name documents to build for, or --examples")
        if seconds <= 0 or memory <= 0:
            raise OptionError("--seconds" if seconds <= 0 else "--memory", "must be positive")
        limits = BuildLimits(seconds, int(memory * 2**20))
        compiler = Compiler()
        rows, failed, seen = [], 0, set()
        for path in paths:
            mech = mechanism(path, None, None)
            for b in builds_of(mech):
                failed += _build(b, path.name, compiler, limits, rows, seen, err)
            for b in window_builds(mech):  # once the kernels it calls are there
                failed += _build(b, path.name, compiler, limits, rows, seen, err)
        table = table_of(
            "kernels", "document", "kernel", "part", "status", "C (kB)", "compile (s)", "peak (MiB)", text=4
        )
        for r in rows:
            numbers = (
                [f"{r['c_bytes'] / 1e3:.0f}", f"{r['seconds']:.1f}", f"{r['peak_bytes'] / 2**20:.0f}"]
                if "c_bytes" in r
                else ["", "", ""]
            )
            table.add_row(shown(r["document"]), r["kernel"], r["part"], r["status"], *numbers)
        out.print(table)
        for r in rows:
            if r["status"] == "abandoned":
                out.print(f"{r['kernel']} {r['part']}: {shown(r['message'])}")
        if json_out is not None:
            write_json(json_out, {"kernels": rows})
    if failed:
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _build(b, document: str, compiler, limits, rows: list, seen: set, err) -> int:
    """Compile what a Build holds that is not there yet (a row each): how many failed."""
    from flexmech.service.kernels.queue import note_abandoned

    failed = 0
    for part, fn, target in b.functions:
        if str(target) in seen:
            continue
        seen.add(str(target))
        if target.exists():
            rows.append({"document": document, "kernel": b.name, "part": part, "status": "cached"})
            continue
        err.print(f"compiling {b.name} {part} ({document})", highlight=False)
        outcome = compiler.build(fn, target, limits, link=b.link)
        if not outcome.ok:
            failed += 1
            if not outcome.retry:  # its files removed under it (the cache's bound): not the Function's fault
                note_abandoned(b.note, outcome)
        rows.append(
            {
                "document": document,
                "kernel": b.name,
                "part": part,
                "status": "built" if outcome.ok else "abandoned",
                **outcome.to_json(),
            }
        )
    return failed
