"""First and repeated solves, now and before the open core (issue 11), side by side in one run.

For every example document, a fresh Python process compiles it and solves its equilibrium
(outputs included), timed from after the imports:
  cold   an empty cache folder (FLEXMECH_CACHE_DIR): the graphs are built
  warm   a second process on the same folder: the graphs are loaded from disk
Then the repeated warm solve of examples/gripper_exact.json (median of many), while two
other processes keep both cores busy (started here).

"Before" is the same measurement on the code of another revision (default: the commit
before issue 11, af77ffc), checked out into a temporary git worktree; documents it cannot read
(families it did not have) show n/a. Run from the repository root:

    python3 -m benchmarks.startup [--before REV] [--repeats 200] [--only gripper_exact]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BEFORE = "af77ffc"
REPEATED = "gripper_exact"

# Runs in the measured tree (its own models and service packages first on sys.path).
PROBE = r"""
import json, statistics, sys, time
started = time.perf_counter()
from flexmech.models import compile_mechanism, load_document
from flexmech.service.solvers.equilibrium import solve_equilibrium
imported = time.perf_counter()
path, repeats = sys.argv[1], int(sys.argv[2])
try:
    mech = compile_mechanism(load_document(path))
    result = solve_equilibrium(mech)
    result.outputs()
except Exception as exc:
    print(json.dumps({"error": f"{type(exc).__name__}: {exc}"[:200]}))
    raise SystemExit(0)
first = time.perf_counter()
times = []
for _ in range(repeats):
    t = time.perf_counter()
    solve_equilibrium(mech)
    times.append(time.perf_counter() - t)
print(json.dumps({"imports": imported - started, "first": first - imported, "status": result.status,
                  "repeated": statistics.median(times) if times else None}))
"""


def probe(tree: Path, document: Path, cache: Path, repeats: int = 0) -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree), "FLEXMECH_CACHE_DIR": str(cache)}
    done = subprocess.run(
        [sys.executable, "-c", PROBE, str(document), str(repeats)],
        cwd=tree,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    if done.returncode != 0:
        return {"error": done.stderr.strip().splitlines()[-1][:200] if done.stderr.strip() else "failed"}
    return json.loads(done.stdout.strip().splitlines()[-1])


@contextmanager
def worktree(rev: str):
    folder = Path(tempfile.mkdtemp(prefix="flexmech-before-"))
    subprocess.run(["git", "worktree", "add", "--detach", str(folder), rev], cwd=ROOT, check=True, capture_output=True)
    try:
        yield folder
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(folder)], cwd=ROOT, capture_output=True)


@contextmanager
def busy_cores(count: int = 2):
    """Processes that keep `count` cores busy while the block runs."""
    spinners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(count)]
    try:
        yield
    finally:
        for spinner in spinners:
            spinner.kill()
            spinner.wait()


def first_solves(trees: dict[str, Path], documents: list[Path]) -> dict:
    """{document: {tree: (cold, warm)}} in seconds (None where it could not run)."""
    table = {}
    for document in documents:
        row = {}
        for label, tree in trees.items():
            with tempfile.TemporaryDirectory(prefix="flexmech-cache-") as cache:
                cold = probe(tree, document, Path(cache))
                warm = probe(tree, document, Path(cache))
            row[label] = (cold.get("first"), warm.get("first"))
        table[document.stem] = row
        print(f"  {document.stem:22s}" + "".join(_cells(row[label]) for label in trees), flush=True)
    return table


def _cells(pair: tuple[float | None, float | None]) -> str:
    return "".join(f"{'n/a':>10s}" if t is None else f"{t * 1e3:10.0f}" for t in pair)


def repeated_solves(trees: dict[str, Path], document: Path, repeats: int) -> dict[str, float | None]:
    out = {}
    for label, tree in trees.items():
        with tempfile.TemporaryDirectory(prefix="flexmech-cache-") as cache:
            probe(tree, document, Path(cache))  # build and save the graphs
            with busy_cores(2):
                out[label] = probe(tree, document, Path(cache), repeats).get("repeated")
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", default=BEFORE, help="revision to compare with (default: %(default)s)")
    parser.add_argument("--repeats", type=int, default=200, help="repeated solves, for the median")
    parser.add_argument("--only", nargs="*", help="example names (default: every example)")
    args = parser.parse_args()
    documents = sorted((ROOT / "examples").glob("*.json"))
    if args.only:
        documents = [d for d in documents if d.stem in args.only]
    with worktree(args.before) as old:
        trees = {f"before ({args.before})": old, "now": ROOT}
        print("first solve in a fresh process, imports excluded [ms]: cold (empty cache), warm (cache filled)")
        print(f"  {'example':22s}" + "".join(f"{label + ' cold':>10s}{'warm':>10s}" for label in ("before", "now")))
        table = first_solves(trees, documents)
        repeated = repeated_solves(trees, ROOT / "examples" / f"{REPEATED}.json", args.repeats)
    row = table.get(REPEATED)
    if row:
        (_, before_warm), (_, now_warm) = row.values()
        if before_warm and now_warm:
            print(
                f"\n{REPEATED}: warm first solve now {now_warm * 1e3:.0f} ms, before {before_warm * 1e3:.0f} ms "
                f"(ratio {before_warm / now_warm:.1f}x)"
            )
    (before_label, before_time), (_, now_time) = repeated.items()
    print(
        f"repeated warm solve of {REPEATED}, both cores loaded by two other processes, median of {args.repeats}: "
        f"before {before_time * 1e3:.2f} ms, now {now_time * 1e3:.2f} ms (ratio {before_time / now_time:.1f}x)"
    )


if __name__ == "__main__":
    main()
