"""Compiled speed without a manual step (issue 48): on an empty cache, a long four-bar run
compiles its kernels first (the progress says so) and steps compiled; the rod's short run stays
interpreted, says what compiling gives and leaves its kernels compiled; the next run of either
is compiled; and no process outlives the command, interrupted or not. Real processes (the
command as users run it), each test on a cache of its own."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

COMMAND = [sys.executable, "-m", "flexmech.api.cli", "simulate"]


def environment(cache: Path) -> dict[str, str]:
    return {**os.environ, "FLEXMECH_CACHE_DIR": str(cache), "COLUMNS": "200", "NO_COLOR": "1"}


def as_in_a_terminal() -> None:
    """Ctrl-C as a terminal delivers it: a process started in the background (a CI job, a shell's
    `&`) inherits SIGINT ignored, and Python then never raises KeyboardInterrupt."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def survivors(cache: Path) -> list[str]:
    """Processes whose environment names this cache (the command's own, a build, a compiler)."""
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            environ = Path(f"/proc/{pid}/environ").read_bytes().split(b"\0")
            command = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if f"FLEXMECH_CACHE_DIR={cache}".encode() in environ and int(pid) != os.getpid():
            found.append(f"{pid}: {command}")
    return found


def simulate(cache: Path, *arguments: str) -> subprocess.CompletedProcess:
    return subprocess.run([*COMMAND, *arguments], env=environment(cache), capture_output=True, text=True, timeout=600)


def gone(cache: Path, within: float = 10.0) -> list[str]:
    deadline = time.monotonic() + within
    while (left := survivors(cache)) and time.monotonic() < deadline:
        time.sleep(0.1)
    return left


def test_a_long_run_compiles_first_and_the_next_runs_compiled(tmp_path):
    cache = tmp_path / "cache"
    run = subprocess.Popen(
        [*COMMAND, "four_bar_dynamics", "--until", "5"],
        env=environment(cache),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=as_in_a_terminal,
    )
    lines = []
    try:
        for line in run.stderr:  # the progress, a line at a time (not a terminal)
            lines.append(line)
            if line.startswith("simulating compiled: t = ") and "steps" in line:
                break  # stepping compiled: interrupt it as Ctrl-C would
        run.send_signal(signal.SIGINT)
        run.wait(60)
    finally:
        run.kill()
    said = "".join(lines)
    assert "simulating interpreted: compiling its kernels first" in said, said
    assert "stopped at t = " in said and "to run compiled" in said, said
    assert gone(cache) == []  # interrupted: nothing it started runs on
    again = simulate(cache, "four_bar_dynamics", "--until", "0.1")
    assert again.returncode == 0, again.stderr[-2000:]
    assert "steps in" in again.stdout and "(compiled)" in again.stdout, again.stdout
    assert "interpreted" not in again.stderr


def test_a_short_run_stays_interpreted_says_so_and_leaves_its_kernels_compiled(tmp_path):
    cache = tmp_path / "cache"
    first = simulate(cache, "rod_free_vibration", "--until", "1")
    assert first.returncode == 0, first.stderr[-2000:]
    assert "(interpreted)" in first.stdout
    hint = " ".join(first.stderr.split())  # one line, however the console wrapped it
    assert "ran interpreted: its kernels were not compiled" in hint and "the next run is compiled" in hint
    assert "flexmech build DOCUMENT" in hint
    assert survivors(cache) == []
    second = simulate(cache, "rod_free_vibration", "--until", "1")
    assert second.returncode == 0 and "(compiled)" in second.stdout, second.stdout
    assert "ran interpreted" not in second.stderr


@pytest.mark.parametrize("wait", [0.0, 2.0])
def test_an_interrupted_run_or_build_leaves_no_process(tmp_path, wait):
    """Ctrl-C while the run steps interpreted beside its build (at once), or while the command
    waits for the build after a short run (2 s in)."""
    cache = tmp_path / "cache"
    run = subprocess.Popen(
        [*COMMAND, "rod_free_vibration", "--until", "0.2"],
        env=environment(cache),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        preexec_fn=as_in_a_terminal,
    )
    try:
        deadline = time.monotonic() + 60
        while not any("build" in s for s in survivors(cache)) and time.monotonic() < deadline:
            time.sleep(0.05)  # its build has started
        assert any("build" in s for s in survivors(cache)), "no build started"
        time.sleep(wait)
        run.send_signal(signal.SIGINT)
        run.wait(60)
    finally:
        run.kill()
    assert gone(cache) == []
