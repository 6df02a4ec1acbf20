"""Progress of a simulation on the command line, over the whole run: the stepping (simulated
time, steps, the time left), then the parts after it (building the report, writing each file),
then a last line with the time each took.

In a terminal, a bar: it fills with simulated time, then pulses under the name of the part that
runs. In a log or a pipe, plain lines: the first as soon as the first window of steps is done,
then one at each tenth of the simulated time and at least every LINE_SECONDS, the last step's,
one per part after the stepping, and the last line; so a batch job's log shows that it runs,
how fast, and what it does once the steps are done."""

from __future__ import annotations

import time
from collections.abc import Callable
from types import TracebackType

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from flexmech.api.cli.common import shown

LINE_SECONDS = 5.0
LINES_PER_RUN = 10  # a line per tenth of the simulated time
END = 1 - 1e-9  # a fraction of the end time that is the end (a sum of steps falls short by rounding)


def seconds_text(seconds: float) -> str:
    return f"{seconds:.1f} s" if seconds < 600 else f"{seconds / 60:.1f} min"


class SimulationProgress:
    """A context manager; calling it with (t, steps) reports the stepping has reached t (s);
    stage(name) starts a part of the run after it; finish() prints the last line."""

    def __init__(self, console: Console, until: float, label: str = "simulating"):
        self.console, self.until, self.label = console, until, label
        self.started = time.monotonic()
        self.last_line = -float("inf")
        self.last_tenth = -1
        self.stages: list[tuple[str, float]] = []  # (name, when it started), after the stepping
        self.bar: Progress | None = None
        if console.is_terminal:
            self.bar = Progress(
                TextColumn("{task.description}"),
                BarColumn(),
                TextColumn("{task.fields[detail]}"),
                TimeElapsedColumn(),
                console=console,
                transient=True,
            )
            self.task = self.bar.add_task(label, total=until, detail="")

    def __enter__(self) -> SimulationProgress:
        if self.bar is not None:
            self.bar.__enter__()
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        if self.bar is not None:
            self.bar.__exit__(kind, error, trace)

    def __call__(self, t: float, steps: int | None = None) -> None:
        now = time.monotonic()
        if self.bar is not None:
            self.bar.update(self.task, completed=t, detail=self.detail(t, steps, now - self.started))
            return
        done = t >= END * self.until
        tenth = LINES_PER_RUN if done else int(LINES_PER_RUN * t / self.until)
        if now - self.last_line < LINE_SECONDS and tenth <= self.last_tenth and not done:
            return
        self.last_line, self.last_tenth = now, tenth
        self.console.print(self.line(t, steps, now - self.started), soft_wrap=True, highlight=False)

    def stepping(self) -> Callable[[float, int | None], None]:
        """The callback a run reports its steps to: once they reach the end time, the part after
        them, building the report, has begun."""

        def heard(t: float, steps: int | None = None) -> None:
            self(t, steps)
            if t >= END * self.until and not self.stages:
                self.stage("building the report")

        return heard

    def stage(self, name: str) -> None:
        """A part of the run after the stepping begins (and the one before it, if any, ends)."""
        now = time.monotonic()
        self.stages.append((name, now))
        if self.bar is not None:
            self.bar.update(self.task, description=name, total=None, detail="")
            return
        self.console.print(f"{self.label}: {shown(name)} ({seconds_text(now - self.started)} elapsed)", highlight=False)

    def finish(self, summary: str = "done") -> None:
        """The last line: `summary`, the whole time, and what the stepping and each part took."""
        now = time.monotonic()
        if self.bar is not None:
            self.bar.update(self.task, visible=False)
        marks = [("stepping", self.started)] + self.stages
        parts = [
            f"{name} {seconds_text(end - start)}" for (name, start), (_, end) in zip(marks, marks[1:] + [("", now)])
        ]
        self.console.print(
            f"{self.label}: {shown(summary)} in {seconds_text(now - self.started)} ({', '.join(parts)})",
            soft_wrap=True,
            highlight=False,
        )

    def detail(self, t: float, steps: int | None, elapsed: float) -> str:
        fraction = min(1.0, t / self.until)
        eta = f", ETA {seconds_text(elapsed * (1 - fraction) / fraction)}" if fraction > 0 else ""
        counted = f", {steps} steps" if steps is not None else ""
        return f"t = {t:.4g} / {self.until:g} s{counted}{eta}"

    def line(self, t: float, steps: int | None, elapsed: float) -> str:
        fraction = min(1.0, t / self.until)
        eta = elapsed * (1 - fraction) / fraction if fraction > 0 else float("nan")
        counted = f", {steps} steps" if steps is not None else ""
        return (
            f"{self.label}: t = {t:.4g} of {self.until:g} s ({100 * fraction:.0f} %){counted}, "
            f"{elapsed:.1f} s elapsed, ETA {eta:.0f} s"
        )
