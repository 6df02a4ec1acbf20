"""What an export's C costs (issue 54): for the shipped examples that export and for families of
growing links up to the largest the limits allow, the unknowns, the row groups' instructions
(service.export.size_model's prediction, and the generated C's largest function as written),
the bytes of C, the seconds to write it, and gcc's build: `make` (one job, the export's own
flags: -std=c99 -O2 -Wall -Wextra -Werror) under /usr/bin/time -v, its CPU seconds (user +
system: the wall time of an idle core), wall seconds and peak memory (the largest child, MB).
Each build runs once; a family stops after a build that passes --stop seconds (or is killed at
--timeout), and at a size over the export's unknowns limit; the predicted seconds and MB are the
model's, beside what was measured (*: a function above the model's quadratic range, the faster
regime's figures). Last, the model's constants as fitted to these rows, and its errors.

    python3 -m benchmarks.export_size [--only examples,link,order8,...] [--no-build] [--json F]
    python3 -m benchmarks.export_size --table F...   (the rows of --json files, with the model now)

Needs gcc and make (scripts/c-tools-for-tests installs them). The graphs are built in a
temporary cache (FLEXMECH_CACHE_DIR), so the writing is timed as a cold job's.
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import json
import math
import os
import re
import resource
import signal
import subprocess
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FUNCTION_HEAD = re.compile(r"^(?:static int|CASADI_SYMBOL_EXPORT int) \w+\(", re.M)
STRAINS = {"shear": True, "axial": True}
# family: (what it is, the cantilever's beam fields, the sizes (intervals) in order)
FAMILIES = {
    "link": ("link by shooting, order 12", {"order": 12}, (4, 8, 16, 24, 32, 56)),
    "order8": ("link by shooting, order 8", {"order": 8}, (16, 24, 30, 40, 64)),
    "order4": ("link by shooting, order 4", {"order": 4}, (32, 64, 79, 96)),
    "strains": ("link by shooting, order 12, shear + axial", {"order": 12, **STRAINS}, (4, 8, 9, 12, 16)),
    "elements3": ("link by elements, degree 3", {"discretization": "elements", "degree": 3}, (16, 32, 52, 64)),
    "elements": (
        "link by elements, degree 6, shear + axial",
        {"discretization": "elements", "degree": 6, **STRAINS},
        (2, 4, 8, 16, 32, 64),
    ),
    # the issue's: the largest link the graph-work limit takes (56 x 12^2 = 8064 of 8192)
    "issue": ("the issue's link, order 12, shear + axial", {"order": 12, **STRAINS}, (56,)),
    # the contact task's KKT kernel: gripper_ellipse_contact's finger in more intervals has more
    # surface rows against the ellipse (3 per interval), each with its second derivatives. Built
    # past the export's limits (which would leave the contact task out), to show where they are.
    "contact": ("ellipse contact, finger intervals", {"example": "gripper_ellipse_contact"}, (1, 2, 3, 4, 5)),
}


def cantilever(fields: dict, intervals: int):
    """examples/cantilever.json with its beam's discretization `fields` and `intervals` (its
    section given an area and its material a Poisson's ratio, for shear and axial strain); or,
    with an "example" field, that contact example with its finger in `intervals`."""
    from flexmech.models.documents.document import MechanismDocument

    if "example" in fields:
        doc = json.loads((ROOT / "examples" / f"{fields['example']}.json").read_text())
        doc["elements"]["finger"]["intervals"] = intervals
        return MechanismDocument.model_validate(doc)
    doc = json.loads((ROOT / "examples" / "cantilever.json").read_text())
    doc["sections"]["thesis"]["A"] = 20.0
    doc["materials"]["steel"]["nu"] = 0.3
    doc["elements"]["beam"].update(copy.deepcopy(fields), intervals=intervals)
    return MechanismDocument.model_validate(doc)


def document_of(source: list):
    """["example", stem] or ["family", name, intervals]: the document measured."""
    from flexmech.models import load_document

    if source[0] == "example":
        return load_document(ROOT / "examples" / f"{source[1]}.json")
    return cantilever(FAMILIES[source[1]][1], source[2])


def largest_function_lines(source: str) -> int:
    """Lines of the largest function of the generated kernels (a function of the row groups:
    about one line per instruction)."""
    starts = [m.start() for m in FUNCTION_HEAD.finditer(source)] + [len(source)]
    return max((source.count("\n", a, b) for a, b in zip(starts, starts[1:])), default=0)


@contextlib.contextmanager
def contact_past_the_limits(family: bool):
    """A family's contact kernel written whatever its predicted build (the export would leave it
    out past the limits): the benchmark measures where they are."""
    from flexmech.service.export import contact_kernels

    if not family:
        yield
        return
    bound = contact_kernels.build_over_limits
    contact_kernels.build_over_limits = lambda size: None
    try:
        yield
    finally:
        contact_kernels.build_over_limits = bound


def with_contact_kernel(mech):
    """The predicted size with the contact task's KKT kernel (service.export.contact_kernels)."""
    from flexmech.service.export.contact_kernels import contact_kernel
    from flexmech.service.export.size_model import row_groups, size_of

    return size_of((*row_groups(mech.structure), contact_kernel(mech)[4]))


def write(document, folder: Path, family: bool = False) -> dict:
    """Export `document` into `folder`: unknowns, the model's prediction, bytes and seconds."""
    from flexmech.models import compile_mechanism
    from flexmech.service.export.library import export_library
    from flexmech.service.export.plan import ExportOptions
    from flexmech.service.export.size_model import predicted_size

    mech = compile_mechanism(document, None)
    started = time.perf_counter()
    predicted = predicted_size(mech.structure)
    model_ms = (time.perf_counter() - started) * 1e3
    started = time.perf_counter()
    with contact_past_the_limits(family):
        manifest = export_library(mech, folder, "as in the document", ExportOptions(name="x"))
    seconds = time.perf_counter() - started
    if "contact" in manifest["tasks"]:  # its kernel, counted as the export counts it when writing
        predicted = with_contact_kernel(mech)
    sources = [p for p in folder.iterdir() if p.suffix in (".c", ".h")]
    return {
        "unknowns": mech.n_free,
        "tasks": manifest["tasks"],
        "predicted": predicted,
        "model_ms": model_ms,
        "c_bytes": sum(p.stat().st_size for p in sources),
        "largest_lines": largest_function_lines((folder / "x_kernels.c").read_text()),
        "write_s": seconds,
    }


def build(folder: Path, timeout: float) -> dict:
    """make (one job) in `folder`: CPU and wall seconds and the peak memory of its largest child."""
    timed = Path("/usr/bin/time").exists()
    command = (["/usr/bin/time", "-v"] if timed else []) + ["make", "-s", "-C", str(folder), "all"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, process_group=0)
    try:
        _, stderr = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:  # the compiler too, not make alone
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        return {"gcc_s": float("inf"), "wall_s": timeout, "peak_mb": float("nan"), "ok": False}
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    peak = after.ru_maxrss
    found = re.search(r"Maximum resident set size \(kbytes\): (\d+)", stderr)
    if found:
        peak = int(found.group(1))
    return {"gcc_s": cpu, "wall_s": wall, "peak_mb": peak / 1024, "ok": proc.returncode == 0}


def measure(label: str, source: list, args) -> dict:
    with tempfile.TemporaryDirectory(prefix="flexmech-export-size-") as scratch:
        folder = Path(scratch) / "x"
        row = {"case": label, "source": source, **write(document_of(source), folder, source[0] == "family")}
        if not args.no_build:
            row.update(build(folder, args.timeout))
    print_row(row)
    return row


HEADER = (
    f"| {'case':<44} | unknowns | predicted instr. (largest) | largest fn lines | C bytes | predicted | "
    "write s | gcc CPU s | wall s | predicted s | peak MB | predicted MB |"
)


def print_row(row: dict) -> None:
    p = row["predicted"]
    gcc = row.get("gcc_s")
    cpu = "-" if gcc is None else (f">{row['wall_s']:.0f}" if gcc == float("inf") else f"{gcc:.1f}")
    wall = "-" if gcc is None else f"{row['wall_s']:.1f}"
    peak = "-" if gcc is None else f"{row['peak_mb']:.0f}"
    failed = "" if row.get("ok", True) else " (make failed)"
    print(
        f"| {row['case'] + failed:<44} | {row['unknowns']:>8} | {p.instructions:>9,} ({p.largest.instructions:>7,}) | "
        f"{row['largest_lines']:>16,} | {row['c_bytes']:>10,} | {p.c_bytes:>10,} | {row['write_s']:>7.2f} | "
        f"{cpu:>9} | {wall:>6} | {p.gcc_seconds:>10.1f}{'*' if p.beyond else ' '} | {peak:>7} | {p.gcc_megabytes:>12.0f} |",
        flush=True,
    )


def examples(args) -> list[dict]:
    from flexmech.models import MechanismError

    rows = []
    for path in sorted((ROOT / "examples").glob("*.json")):
        try:
            rows.append(measure(path.stem, ["example", path.stem], args))
        except MechanismError as exc:  # dynamics-only documents, a free mechanism: no export
            print(f"| {path.stem:<44} | not exported: {exc.pointer}: {exc.problem[:80]}", flush=True)
    return rows


def family(name: str, args) -> list[dict]:
    from flexmech.models import compile_mechanism
    from flexmech.service.costs import Limits

    what, fields, sizes = FAMILIES[name]
    rows = []
    for intervals in sizes:
        unknowns = compile_mechanism(cantilever(fields, intervals), None).n_free
        if unknowns > Limits().max_export_unknowns:  # refused before its size counts (and slow to write)
            print(f"| {what}: {intervals} | {unknowns} unknowns: refused (limit {Limits().max_export_unknowns})")
            break
        row = measure(f"{what}: {intervals}", ["family", name, intervals], args)
        rows.append(row)
        if row.get("gcc_s", 0.0) > args.stop:
            break
    return rows


def predicted(source: list, tasks: list[str]):
    from flexmech.models import compile_mechanism
    from flexmech.service.export.size_model import predicted_size

    mech = compile_mechanism(document_of(source), None)
    return with_contact_kernel(mech) if "contact" in tasks else predicted_size(mech.structure)


def quadratic(rows: list[dict]) -> list[dict]:
    """The built family rows in gcc's quadratic regime: their largest function within the model's
    range, and their time grown at least in proportion to the size since the family's previous
    size (after a size that has not, gcc has dropped its quadratic passes)."""
    from flexmech.service.export.size_model import GCC_PREDICTED_UP_TO

    found, previous = [], {}
    built = [r for r in rows if r["source"][0] == "family" and math.isfinite(r.get("gcc_s", math.nan))]
    for r in sorted(built, key=lambda r: (r["source"][1], r["source"][2])):
        size, name = r["predicted"].largest.instructions, r["source"][1]
        slower = name not in previous or (previous[name] and r["gcc_s"] >= previous[name][1] * size / previous[name][0])
        previous[name] = (size, r["gcc_s"]) if slower and size <= GCC_PREDICTED_UP_TO else None
        if previous[name]:
            found.append(r)
    return found


def fit(rows: list[dict]) -> None:
    """The fits of service.export.size_model's constants to the links' rows, and its errors over
    them, the examples and the contact kernels (not fitted to: they test the model)."""
    import numpy as np

    from flexmech.service.export import size_model as m

    contact = [r for r in rows if r["source"][:2] == ["family", "contact"]]
    rows = [r for r in rows if r not in contact]
    errors("the contact kernels (not fitted to)", contact)
    if len(rows) < 3:
        return
    groups = [[g.instructions for g in r["predicted"].groups] for r in rows]
    X = np.array([[1.0, sum(gs), sum(L * math.log10(L / 1e4) for L in gs)] for gs in groups])
    measured = np.array([r["c_bytes"] for r in rows], float)
    c = np.linalg.lstsq(X / measured[:, None], np.ones(len(rows)), rcond=None)[0]  # least relative squares
    print(f"\nC bytes = {c[0]:,.0f} + sum L x ({c[1]:.2f} + {c[2]:.2f} log10(L / 10,000)) over {len(rows)} exports")
    fitted = quadratic(rows)
    if len(fitted) < 3:
        return
    largest = [max((g.instructions, g.unknowns) for g in r["predicted"].groups) for r in fitted]
    X = np.array([[1.0, math.log(L / 1e4), math.log(max(n, 1) / 64)] for L, n in largest])
    s = np.linalg.lstsq(X, np.log([r["gcc_s"] - m.GCC_BASE_SECONDS for r in fitted]), rcond=None)[0]
    print(
        f"gcc s = {m.GCC_BASE_SECONDS} + sum {math.exp(s[0]):.2f} (L/1e4)^{s[1]:.2f} (n/64)^{s[2]:.2f} ({len(fitted)} links)"
    )
    parse = [m.GCC_BASE_MEGABYTES + m.GCC_PARSE_MEGABYTES_PER_INSTRUCTION * r["predicted"].instructions for r in fitted]
    y = np.log([max(r["peak_mb"] - p, 1.0) for r, p in zip(fitted, parse)])
    b = np.linalg.lstsq(X, y, rcond=None)[0]
    print(f"gcc MB = parse + {math.exp(b[0]):.1f} (L/1e4)^{b[1]:.2f} (n/64)^{b[2]:.2f} (the largest function)")
    switched = [r for r in rows if r["source"][0] == "family" and r not in fitted and math.isfinite(r.get("gcc_s", 0))]
    for what, over in (("the examples", [r for r in rows if r["source"][0] == "example"]), ("the links", fitted)):
        errors(what, over)
    errors("where gcc dropped its quadratic passes (the model over)", switched)


def errors(what: str, rows: list[dict]) -> None:
    built = [r for r in rows if math.isfinite(r.get("gcc_s", math.nan))]
    for label, key, model, over in (
        ("C bytes", "c_bytes", "c_bytes", rows),
        ("gcc s", "gcc_s", "gcc_seconds", built),
        ("gcc MB", "peak_mb", "gcc_megabytes", built),
    ):
        found = sorted((getattr(r["predicted"], model) / r[key] - 1, r["case"]) for r in over)
        if found:
            print(f"{what}: {label} {found[0][0]:+.0%} ({found[0][1]}) .. {found[-1][0]:+.0%} ({found[-1][1]})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", default="examples," + ",".join(FAMILIES), help="examples and/or families")
    parser.add_argument("--no-build", action="store_true", help="write the C only (no gcc)")
    parser.add_argument("--stop", type=float, default=90.0, help="a family stops after a build this long (s)")
    parser.add_argument("--timeout", type=float, default=300.0, help="a build is killed after this long (s)")
    parser.add_argument("--json", type=Path, help="write the measured rows as JSON")
    parser.add_argument(
        "--table", type=Path, nargs="+", help="print the rows of --json files again, with the model now"
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="flexmech-export-size-cache-") as cache:
        os.environ.setdefault("FLEXMECH_CACHE_DIR", cache)
        run(args)


def run(args) -> None:
    print(HEADER)
    print("|" + "|".join("---" for _ in range(12)) + "|")
    if args.table:
        rows = [row for path in args.table for row in json.loads(path.read_text())]
        for row in rows:
            row["predicted"] = predicted(row["source"], row["tasks"])
            print_row(row)
    else:
        rows = []
        for name in args.only.split(","):
            rows += examples(args) if name == "examples" else family(name, args)
    if args.json:
        plain = [{k: v for k, v in r.items() if k != "predicted"} for r in rows]
        args.json.write_text(json.dumps(plain, indent=1) + "\n")
    fit(rows)
    slowest = max((r.get("model_ms", 0.0) for r in rows), default=0.0)
    print(f"the model's prediction took at most {slowest:.2f} ms per export (before any code is generated)")


if __name__ == "__main__":
    main()
