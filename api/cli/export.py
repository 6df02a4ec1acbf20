"""`flexmech export DOC --c DIR`: the mechanism's solver as a C99 library for controllers
(service.export): equilibrium, tangent stiffness and target tasks with a header, manifest,
Makefile, CMakeLists.txt, example sweep, benchmark, checks and a ctypes loader. With --build,
compiles it (make) and runs its checks and benchmark here."""

from __future__ import annotations

import subprocess
from pathlib import Path
from typing import Annotated

import typer

from flexmech.api.cli.application import app
from flexmech.api.cli.common import EXIT_NOT_CONVERGED, OptionError, consoles, shown, table_of, user_errors, write_json
from flexmech.api.cli.options import DocArg, JsonOpt, ModelOpt, SetOpt, mechanism

BUILD_SECONDS = 600  # a large exact model's kernels take about a minute at -O2


def _ranges(items: list[str] | None) -> dict[str, tuple[float, float]]:
    out = {}
    for item in items or []:
        pointer, sep, span = item.partition("=")
        low, colon, high = span.partition(":")
        try:
            if not (sep and colon):
                raise ValueError
            out[pointer.strip()] = (float(low), float(high))
        except ValueError:
            raise OptionError("--range", f"expected POINTER=LOW:HIGH, got '{item}'") from None
    return out


def _target(target: str | None, by: str | None):
    if target is None and by is None:
        return None
    output, sep, value = (target or "").partition("=")
    if not sep or by is None:
        raise OptionError("--target", "give both --target OUTPUT=VALUE and --by POINTER")
    try:
        return output.strip(), float(value), by
    except ValueError:
        raise OptionError("--target", f"'{value}' is not a number") from None


NameOpt = Annotated[str | None, typer.Option("--name", help="C prefix of the library (default: the file's name).")]
InputOpt = Annotated[
    list[str] | None,
    typer.Option("--input", metavar="POINTER", help="An input field (default: every load). Repeatable."),
]
OutputOpt = Annotated[
    list[str] | None,
    typer.Option("--output", metavar="NAME", help="An output (default: the document's named outputs). Repeatable."),
]
RangeOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--range",
        metavar="POINTER=LOW:HIGH",
        help="An input's range; outside it a call returns OUT_OF_RANGE. Repeatable.",
    ),
]
TargetOpt = Annotated[
    str | None,
    typer.Option(
        "--target",
        metavar="OUTPUT=VALUE",
        help="The target task's output and goal (default: the document's sweep 'until').",
    ),
]
ByOpt = Annotated[str | None, typer.Option("--by", metavar="POINTER", help="The input the target task solves for.")]
ContactOpt = Annotated[
    str, typer.Option("--contact", help="The contact state task: auto (when it can be exported) | yes | no.")
]
ContactOutputOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--contact-output",
        metavar="NAME",
        help="An output of the contact task (default: the document's contact path outputs). Repeatable.",
    ),
]
IterationsOpt = Annotated[int, typer.Option("--max-iterations", help="Newton steps per call, at most.")]
ToleranceOpt = Annotated[
    float, typer.Option("--tolerance", help="Converged when the nondimensional |R|_inf is below it.")
]
BuildOpt = Annotated[bool, typer.Option("--build", help="Compile it (make), run its checks and its benchmark.")]


@app.command()
def export(
    document: DocArg,
    c: Annotated[Path, typer.Option("--c", metavar="DIR", help="Write the C library into this folder.")],
    model: ModelOpt = None,
    sets: SetOpt = None,
    name: NameOpt = None,
    inputs: InputOpt = None,
    outputs: OutputOpt = None,
    ranges: RangeOpt = None,
    target: TargetOpt = None,
    by: ByOpt = None,
    contact: ContactOpt = "auto",
    contact_outputs: ContactOutputOpt = None,
    max_iterations: IterationsOpt = 30,
    tolerance: ToleranceOpt = 1e-12,
    build: BuildOpt = False,
    json_out: JsonOpt = None,
) -> None:
    """Export the mechanism's solver as dependency-free C99 (CasADi code generation) for controllers."""
    from flexmech.service.export.library import export_library
    from flexmech.service.export.plan import ExportOptions

    out, err = consoles()
    with user_errors(err):
        mech = mechanism(document, model, sets)
        options = ExportOptions(
            name=name or document.stem,
            inputs=tuple(inputs or ()),
            outputs=tuple(outputs or ()),
            ranges=_ranges(ranges),
            target=_target(target, by),
            contact=contact,
            contact_outputs=tuple(contact_outputs or ()),
            max_iterations=max_iterations,
            tolerance=tolerance,
        )
        manifest = export_library(mech, c, model or "as in the document", options)
    _print_manifest(out, manifest, c)
    built = _build(out, err, c) if build else None
    if json_out is not None:
        write_json(json_out, {"manifest": manifest, "build": built})
    if built is not None and not built["passed"]:
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _print_manifest(out, manifest: dict, folder: Path) -> None:
    table = table_of(f"{manifest['name']}: inputs and outputs", "", "name", "field", "unit", text=4)
    for item in manifest["inputs"]:
        table.add_row("input", item["name"], shown(item["pointer"]), shown(item["unit"]))
    for item in manifest["outputs"]:
        table.add_row("output", item["name"], shown(item["output"]), shown(item["unit"]))
    out.print(table)
    worst = manifest["worst_case_iterations"]
    out.print(
        f"Newton steps per call at most {manifest['limits']['max_iterations']}; measured over "
        f"{shown(worst['measured_over'])}: warm {worst['equilibrium_warm']}, cold {worst['equilibrium_cold']}"
        + (f", target from cold {worst['target_cold']}" if "target_cold" in worst else "")
    )
    if manifest.get("contact") and "note" in manifest["contact"]:
        out.print(shown(manifest["contact"]["note"]))
    size = sum(p.stat().st_size for p in folder.iterdir() if p.is_file())
    out.print(f"wrote {folder} ({size / 1e3:.0f} kB, {manifest['unknowns']} unknowns); build it with: make -C {folder}")


def _build(out, err, folder: Path) -> dict:
    """make, make check, ./bench in the export's folder (the user's own build, in the foreground)."""
    steps = {
        "make": ["make", "-C", str(folder)],
        "check": ["make", "-C", str(folder), "-s", "check"],
        "bench": [str(folder / "bench")],
    }
    results: dict = {"passed": True}
    for label, command in steps.items():
        try:
            done = _run_in_own_group(command)
        except (OSError, subprocess.TimeoutExpired) as exc:
            err.print(f"[red]{label}: {shown(str(exc))}[/red]")
            results["passed"] = False
            break
        results[label] = done.stdout.strip().splitlines()[-8:]
        if done.returncode != 0:
            err.print(f"[red]{label} failed:[/red]\n{shown(done.stdout[-2000:] + done.stderr[-2000:])}")
            results["passed"] = False
            break
        if label != "make":
            out.print(shown(done.stdout.strip()))
    return results


def _run_in_own_group(command: list[str]) -> subprocess.CompletedProcess:
    """command in a process group of its own that dies with this process: a time-out or an
    interrupt kills make and every compiler it started, not make alone."""
    import os
    import signal

    from flexmech.service.kernels.build import die_with_parent

    proc = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, process_group=0, preexec_fn=die_with_parent
    )
    try:
        stdout, stderr = proc.communicate(timeout=BUILD_SECONDS)
    except BaseException:  # TimeoutExpired, KeyboardInterrupt: nothing it started outlives it
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait()
        raise
    return subprocess.CompletedProcess(command, proc.returncode, stdout, stderr)
