"""Progress of a simulation on the command line, over the whole run: the stepping (simulated
time, steps, the time left), then the parts after it (building the report, writing each file),
then a last line with the time each took.

In a terminal, a bar: it fills with simulated time, then pulses under the name of the part that
runs. In a log or a pipe, plain lines: the first as soon as the first window of steps is done,
then one at each tenth of the simulated time and at least every LINE_SECONDS, the last step's,
one per part after the stepping, and the last line; so a batch job's log shows that it runs,
how fast, and what it does once the steps are done.

One measured time per part: the last line splits the run into setting up, the stepping (the
run's own measure of it, report["seconds"], which the summary under it prints too), and each
part after it, and they add up to the whole.

The time left (ETA) is the simulated time left over the recent rate of simulated time per wall
time (time_left): adaptive steps that shrink as the motion stiffens slow the run down, and an
estimate from the average rate since the start would promise too little."""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Sequence
from types import TracebackType

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from flexmech.api.cli.common import shown

LINE_SECONDS = 5.0
LINES_PER_RUN = 10  # a line per tenth of the simulated time
END = 1 - 1e-9  # a fraction of the end time that is the end (a sum of steps falls short by rounding)
RECENT = 0.25  # the rate of the ETA is measured over this last share of the wall time since the first step


def seconds_text(seconds: float) -> str:
    """A wall time as the progress and the summaries print it: two figures below a second."""
    if seconds < 1:
        return f"{seconds:.2g} s"
    return f"{seconds:.1f} s" if seconds < 600 else f"{seconds / 60:.1f} min"


def time_left(
    heard: Sequence[tuple[float, float]], until: float, first: float | None = None, recent: float = RECENT
) -> float | None:
    """Wall seconds until the simulated time reaches `until`, from `heard`: (wall time, simulated
    time) of reports of the stepping, oldest first, the first of them at wall time `first`
    (default: the first in `heard`). The rate is simulated time per wall time over the last
    `recent` share of the wall time since the first report (from the latest report at or before
    that share began, so over at least the last two reports); None with fewer than two reports
    or no progress among them. 0 once the end is reached."""
    if not heard:
        return None
    now, t = heard[-1]
    if t >= END * until:
        return 0.0
    since = now - recent * (now - (heard[0][0] if first is None else first))
    earlier = [sample for sample in heard[:-1] if sample[0] <= since]
    then = earlier[-1] if earlier else (heard[-2] if len(heard) > 1 else None)
    if then is None or now <= then[0] or t <= then[1]:
        return None
    return (until - t) * (now - then[0]) / (t - then[1])


REPORT_STAGE = "building the report"


class SimulationProgress:
    """A context manager; calling it with (t, steps) reports the stepping has reached t (s);
    stage(name) starts a part of the run after it; finish() prints the last line. `clock` gives
    the wall time (s; tests pass their own)."""

    def __init__(
        self, console: Console, until: float, label: str = "simulating", clock: Callable[[], float] = time.monotonic
    ):
        self.console, self.until, self.label, self.clock = console, until, label, clock
        self.started = clock()
        self.last_line = -float("inf")
        self.last_tenth = -1
        self.heard: deque[tuple[float, float]] = deque()  # (wall, simulated) of the recent reports
        self.first_heard: float | None = None
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
        now = self.clock()
        self._heard(now, t)
        if self.bar is not None:
            self.bar.update(self.task, completed=t, detail=self.detail(t, steps, now - self.started))
            return
        done = t >= END * self.until
        tenth = LINES_PER_RUN if done else int(LINES_PER_RUN * t / self.until)
        if now - self.last_line < LINE_SECONDS and tenth <= self.last_tenth and not done:
            return
        self.last_line, self.last_tenth = now, tenth
        self.console.print(self.line(t, steps, now - self.started), soft_wrap=True, highlight=False)

    def _heard(self, now: float, t: float) -> None:
        """Keep the reports time_left reads: the recent ones, and the latest before them."""
        if self.first_heard is None:
            self.first_heard = now
        self.heard.append((now, t))
        since = now - RECENT * (now - self.first_heard)
        while len(self.heard) > 2 and self.heard[1][0] <= since:
            self.heard.popleft()

    def eta(self) -> float | None:
        """The time left at the recent rate (time_left); None (unknown) before two reports: the
        first window of steps carries the one-off costs of starting (kernels loaded, caches)."""
        return time_left(list(self.heard), self.until, self.first_heard)

    def stepping(self) -> Callable[[float, int | None], None]:
        """The callback a run reports its steps to: once they reach the end time, the part after
        them, building the report, has begun."""

        def heard(t: float, steps: int | None = None) -> None:
            if t < END * self.until and [name for name, _ in self.stages] == [REPORT_STAGE]:
                self.again()  # another run began (an accuracy target's next)
            self(t, steps)
            if t >= END * self.until and not self.stages:
                self.stage(REPORT_STAGE)

        return heard

    def again(self) -> None:
        """The stepping goes on with another run: its report's stage was not the last part."""
        self.stages.clear()
        self.heard.clear()
        self.first_heard, self.last_tenth = None, -1
        if self.bar is not None:
            self.bar.update(self.task, description=self.label, total=self.until)

    def stage(self, name: str) -> None:
        """A part of the run after the stepping begins (and the one before it, if any, ends)."""
        now = self.clock()
        self.stages.append((name, now))
        if self.bar is not None:
            self.bar.update(self.task, description=name, total=None, detail="")
            return
        self.console.print(f"{self.label}: {shown(name)} ({seconds_text(now - self.started)} elapsed)", highlight=False)

    def parts(self, stepping: float | None = None) -> list[tuple[str, float]]:
        """(name, seconds) of each part of the run so far, adding up to the whole: the stepping
        (given `stepping`, the run's own measure of it, the rest of that part setting up), then
        each stage."""
        now = self.clock()
        marks = [("stepping", self.started)] + self.stages
        spans = [(name, end - start) for (name, start), (_, end) in zip(marks, marks[1:] + [("", now)])]
        if stepping is not None:
            first = spans[0][1]
            spans[:1] = [("setting up", max(first - stepping, 0.0)), ("stepping", min(stepping, first))]
        return spans

    def finish(self, summary: str = "done", stepping: float | None = None) -> None:
        """The last line: `summary` and its steps' time, the whole time, and what each part took;
        `stepping` is the run's own measure of its steps (report["seconds"]), which the summary
        printed after prints too."""
        if self.bar is not None:
            self.bar.update(self.task, visible=False)
        spans = self.parts(stepping)
        total = sum(seconds for _, seconds in spans)
        parts = ", ".join(f"{name} {seconds_text(seconds)}" for name, seconds in spans)
        took = (
            f"{seconds_text(stepping)}; {seconds_text(total)} in all" if stepping is not None else seconds_text(total)
        )
        self.console.print(f"{self.label}: {shown(summary)} in {took} ({parts})", soft_wrap=True, highlight=False)

    def detail(self, t: float, steps: int | None, elapsed: float) -> str:
        left = self.eta()
        eta = f", ETA {seconds_text(left)}" if left is not None else ""
        counted = f", {steps} steps" if steps is not None else ""
        return f"t = {t:.4g} / {self.until:g} s{counted}{eta}"

    def line(self, t: float, steps: int | None, elapsed: float) -> str:
        fraction = min(1.0, t / self.until)
        left = self.eta()
        counted = f", {steps} steps" if steps is not None else ""
        return (
            f"{self.label}: t = {t:.4g} of {self.until:g} s ({100 * fraction:.0f} %){counted}, "
            f"{elapsed:.1f} s elapsed, ETA {'?' if left is None else f'{left:.0f}'} s"
        )
