"""The `flexmech` script's entry: the command, then an exit without Python's teardown.

Tearing the interpreter down (every module's objects freed one by one: pint's, pydantic's,
CasADi's) takes 0.15-0.2 s after every command, about a twentieth of a cold simulation. Like mypy's
hard exit, main() leaves by os._exit once the command is done and nothing is left to end: the
atexit handlers have run and the streams are flushed. A command that leaves a thread or a
child process behind (a server, a pool, a Dask cluster) exits the ordinary way.
"""

from __future__ import annotations

import atexit
import multiprocessing
import os
import sys
import threading

from flexmech.api.cli.application import app


def exit_code(exc: SystemExit) -> int:
    """The process's exit code for a SystemExit, as Python gives it (a message: printed, 1)."""
    if exc.code is None:
        return 0
    if isinstance(exc.code, int):
        return exc.code
    print(exc.code, file=sys.stderr)
    return 1


def main() -> None:
    """The `flexmech` script: run the command, then leave quickly where nothing else runs."""
    try:
        app()
        code = 0
    except SystemExit as exc:
        code = exit_code(exc)
    if threading.active_count() > 1 or multiprocessing.active_children():
        raise SystemExit(code)
    atexit._run_exitfuncs()  # what an ordinary exit runs first
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe or stream: nothing more can be written
            pass
    os._exit(code)
