"""How long the command line takes to answer --help, in fresh processes (issue 28: under 0.5 s).

Each row is the median wall time of several fresh processes, run one after the other:
  python -c pass               the floor: the interpreter starting and leaving
  flexmech --help              the list of commands (the registry's analyses among them)
  flexmech solve --help        one command's options
  flexmech modes --help        a command made from an analysis' options: it imports the registry
The `flexmech` script next to this Python is run (not a version manager's shim, which adds its
own start); without one, `python -m flexmech.api.cli`. Run from the repository root:

    python3 -m benchmarks.cli_startup [--repeats 9]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def flexmech() -> list[str]:
    """The command that starts the CLI: the installed script, else the package's __main__."""
    script = Path(sys.executable).parent / "flexmech"
    return [str(script)] if script.exists() else [sys.executable, "-m", "flexmech.api.cli"]


def median_seconds(command: list[str], repeats: int) -> float:
    """The median wall time of `repeats` fresh processes of `command` (output discarded)."""
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        subprocess.run(command, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=9, help="fresh processes per row")
    repeats = parser.parse_args().repeats
    cli = flexmech()
    rows = [
        ("python -c pass (floor)", [sys.executable, "-c", "pass"]),
        ("flexmech --help", [*cli, "--help"]),
        ("flexmech solve --help", [*cli, "solve", "--help"]),
        ("flexmech modes --help", [*cli, "modes", "--help"]),
    ]
    subprocess.run([*cli, "--help"], cwd=ROOT, stdout=subprocess.DEVNULL, check=True)  # byte-compiled once
    print(f"{' '.join(cli)}; median of {repeats} fresh processes each")
    for label, command in rows:
        print(f"  {label:<26} {median_seconds(command, repeats):6.3f} s")


if __name__ == "__main__":
    main()
