"""Progress of a simulation on the command line: a bar with simulated time, steps and the time
left in a terminal; in a log or a pipe, a plain line every LINE_SECONDS (and the first one as
soon as the first window is done), so a batch job's log shows that it runs and how fast."""

from __future__ import annotations

import time

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

LINE_SECONDS = 5.0


class SimulationProgress:
    """A context manager; calling it with (t, steps) reports the run has reached t (s)."""

    def __init__(self, console: Console, until: float, label: str = "simulating"):
        self.console, self.until, self.label = console, until, label
        self.started = time.monotonic()
        self.last_line = -float("inf")
        self.bar = None
        if console.is_terminal:
            self.bar = Progress(
                TextColumn("{task.description}"),
                BarColumn(),
                TextColumn("t = {task.completed:.4g} / {task.total:g} s"),
                TextColumn("{task.fields[steps]} steps"),
                TextColumn("ETA"),
                TimeRemainingColumn(),
                console=console,
                transient=True,
            )
            self.task = self.bar.add_task(label, total=until, steps=0)

    def __enter__(self) -> SimulationProgress:
        if self.bar is not None:
            self.bar.__enter__()
        return self

    def __exit__(self, *exc) -> None:
        if self.bar is not None:
            self.bar.__exit__(*exc)

    def __call__(self, t: float, steps: int | None = None) -> None:
        if self.bar is not None:
            self.bar.update(self.task, completed=t, steps=steps if steps is not None else "-")
            return
        now = time.monotonic()
        if now - self.last_line < LINE_SECONDS and t < self.until:
            return
        self.last_line = now
        self.console.print(self.line(t, steps, now - self.started), soft_wrap=True)

    def line(self, t: float, steps: int | None, elapsed: float) -> str:
        fraction = min(1.0, t / self.until)
        eta = elapsed * (1 - fraction) / fraction if fraction > 0 else float("nan")
        counted = f", {steps} steps" if steps is not None else ""
        return (
            f"{self.label}: t = {t:.4g} of {self.until:g} s ({100 * fraction:.0f} %){counted}, "
            f"{elapsed:.1f} s elapsed, ETA {eta:.0f} s"
        )
