"""The server's solver workers: processes that do every piece of CasADi work a request needs
(a solve, a drawing, a job's preparation), so that the process answering requests never holds
the interpreter for a solve (CasADi calls keep the GIL: one long call in the server process
stalled every other request, /v1/health included).

- Workers are processes forked by multiprocessing's fork server (the server has threads, so
  forking the server itself is unsafe), which imports the solvers once: a worker, or its
  replacement, starts in milliseconds. Sized by a setting (default: the core count); worker 0
  starts with the server, the others when a request first needs them. Each keeps its
  own graph caches.
- Two lanes: small requests run on worker 0, so they stay on warm caches; large ones (the
  caller says which: simulations, traces, contact) on the others, so a long run never holds a
  small request. With one worker, both lanes share it.
- Time limit: a call's work stops itself at its limit. Its first solving loop (Newton, IPOPT,
  a trace, a simulation, a drawing) starts the call's one clock, and every loop after it
  stops at the same deadline (service.deadline), which the worker publishes in a value shared
  with the server. A worker still busy GRACE seconds past that deadline is killed, and a new
  one starts in its place; before any loop has started (building a new structure's graphs,
  which the document's costing bounds) it may take the limit plus `build_allowance`. A call
  whose caller went away keeps its worker until its work ends (bounded the same way), so the
  worker's caches are kept.
- A worker that ends unexpectedly (a crash, the OOM killer) is replaced; its call is a 503.
"""

from __future__ import annotations

import asyncio
import ctypes
import logging
import multiprocessing
import pickle
import signal
from concurrent.futures import ThreadPoolExecutor

from flexmech.api.errors import ApiError
from flexmech.models import MechanismError
from flexmech.models.caches.graph_cache import defer_saves, flush_saves
from flexmech.service.deadline import call_scope

log = logging.getLogger("flexmech.solvers")

GRACE = 1.0  # seconds a call may run past its time limit before its worker is replaced
POLL = 0.1  # seconds between looks at a busy worker's deadline
BUILD_ALLOWANCE = 30.0  # seconds of graph building a call may take besides its time limit
RETRY_AFTER = 2  # seconds, in a 503 for a call whose worker ended


# ---- inside a worker ----------------------------------------------------------------------------
WORKER_NAME = b"flexmech-solver"  # what ps and /proc/<pid>/comm show for a worker


def die_with_parent(name: bytes = WORKER_NAME) -> None:
    """Ask Linux to end this process when its parent ends (the fork server, which ends with the
    server process, even on kill -9), and to name it (ps, top)."""
    try:
        libc = ctypes.CDLL("libc.so.6", use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        libc.prctl(15, ctypes.c_char_p(name))  # PR_SET_NAME
    except OSError:  # not Linux: the closed pipe ends the worker at its next call instead
        pass


def _packed(exc: BaseException) -> tuple:
    """An exception as a message that unpickles: our two error types by their fields (their
    constructors take more than the message), others as themselves when they survive a round
    trip, else as their text."""
    if isinstance(exc, MechanismError):
        return "mechanism_error", exc.pointer, exc.problem, exc.problems
    if isinstance(exc, ApiError):
        return "api_error", exc.status, exc.code, exc.message, exc.pointer
    try:
        pickle.loads(pickle.dumps(exc))
        return "error", exc
    except Exception:
        return "error", RuntimeError(f"{type(exc).__name__}: {exc}")


def _serve(connection, name: bytes = WORKER_NAME, deadline=None) -> None:
    """A worker's life: run each (fn, args, kwargs) it is sent and send back its outcome,
    publishing each call's deadline in `deadline` (a shared double; 0: no loop started)."""
    die_with_parent(name)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C in a terminal goes to the server, which ends us
    from flexmech.service.jobs.kinds import job_kinds
    from flexmech.service.threads import single_threaded_blas

    single_threaded_blas()
    job_kinds()  # the solvers' imports now, not in the first request
    defer_saves()  # a new structure's graphs go to the disk cache after its answer, not before
    while True:
        try:
            fn, args, kwargs = connection.recv()
        except (EOFError, OSError):  # the server went away
            return
        try:
            with call_scope(deadline):
                outcome = ("ok", fn(*args, **kwargs))
        except BaseException as exc:  # every failure goes back to the caller, who knows how to answer it
            outcome = _packed(exc)
        try:
            connection.send(outcome)
        except Exception as exc:  # a result that does not pickle
            connection.send(_packed(exc))
        flush_saves(stop=connection.poll)  # while no request waits


def _unpacked(outcome: tuple):
    kind = outcome[0]
    if kind == "ok":
        return outcome[1]
    if kind == "mechanism_error":
        raise MechanismError(*outcome[1:])
    if kind == "api_error":
        raise ApiError(*outcome[1:])
    raise outcome[1]


# ---- in the server --------------------------------------------------------------------------------
class _Worker:
    def __init__(self, context, index: int, name: bytes = WORKER_NAME):
        self.index = index
        self.name = name
        self.connection, theirs = context.Pipe()
        self.deadline = context.Value("d", 0.0, lock=False)  # its call's deadline (time.monotonic); 0: none yet
        self.process = context.Process(
            target=_serve, args=(theirs, name, self.deadline), name=f"{name.decode()}-{index}", daemon=True
        )
        self.process.start()
        theirs.close()

    def end(self) -> None:
        """Kill the worker now (it may be inside a long CasADi call that no signal interrupts)."""
        if self.process.is_alive():
            self.process.kill()
        self.process.join(5)
        self.connection.close()


# What the fork server imports once, so that no worker imports it again.
PRELOAD = [
    "flexmech.api.solver_pool",
    "flexmech.api.routers.solve",
    "flexmech.api.routers.drawings",
    "flexmech.service.analyses",
    "flexmech.service.jobs.contact",
    "flexmech.service.jobs.impact_study",
    "flexmech.service.jobs.optimize",
    "flexmech.service.jobs.simulation",
    "flexmech.service.jobs.sweep",
]


class SolverPool:
    """`await pool.call(fn, *args, time_limit=..., large=...)` runs fn(*args) in a worker
    process; fn, its arguments and its result must pickle (module-level functions, pydantic
    models, dataclasses)."""

    def __init__(self, workers: int, build_allowance: float = BUILD_ALLOWANCE, name: bytes = WORKER_NAME):
        self.build_allowance = build_allowance
        self.name = name  # the workers' process name
        self._context = multiprocessing.get_context("forkserver")
        self._context.set_forkserver_preload(PRELOAD)
        self._workers: list[_Worker | None] = [_Worker(self._context, 0, name)] + [None] * (workers - 1)
        self._idle = set(range(workers))
        self._changed: asyncio.Condition | None = None
        # one thread per worker waits on its pipe, so the event loop never blocks on a result
        self._readers = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="flexmech-solver-reader")
        self.description = f"{workers} solver worker{'s' if workers != 1 else ''}"

    @property
    def pids(self) -> list[int]:
        return [w.process.pid for w in self._workers if w is not None]

    def _choice(self, large: bool) -> int | None:
        """Two lanes: small requests on worker 0 (its caches warm with them), large ones on the
        others (all on worker 0 when there is only one). Small requests once also took an idle
        other worker, and paid for its cold caches: the abuse test's small-solve p99 went from
        under 100 ms to 329 ms."""
        if not large or len(self._workers) == 1:
            return 0 if 0 in self._idle else None
        allowed = self._idle - {0}
        return min(allowed) if allowed else None

    async def _take(self, large: bool) -> int:
        if self._changed is None:
            self._changed = asyncio.Condition()
        async with self._changed:
            await self._changed.wait_for(lambda: self._choice(large) is not None)
            index = self._choice(large)
            self._idle.discard(index)
            return index

    async def _give_back(self, index: int) -> None:
        async with self._changed:
            self._idle.add(index)
            self._changed.notify_all()

    def _replace(self, index: int, why: str) -> None:
        old = self._workers[index]
        log.warning("%s %d (pid %s) replaced: %s", self.name.decode(), index, old.process.pid, why)
        old.end()
        self._workers[index] = None  # a new one starts when a request needs it

    async def call(self, fn, *args, time_limit: float | None = None, large: bool = False, **kwargs):
        index = await self._take(large)
        if self._workers[index] is None:
            self._workers[index] = _Worker(self._context, index, self.name)
        worker = self._workers[index]
        loop = asyncio.get_running_loop()
        started = loop.time()  # loop.time() is time.monotonic(): the workers' clock
        give_back = True
        try:
            worker.connection.send((fn, args, kwargs))
            wait = loop.run_in_executor(self._readers, worker.connection.recv)
            outcome = await self._within_limit(worker, wait, started, time_limit)
        except TimeoutError as late:
            wait.add_done_callback(lambda f: f.exception())  # the killed worker's end of pipe: expected
            self._replace(index, f"still busy {late} (time limit {time_limit:g} s)")
            raise ApiError(503, "time_limit", f"the work did not end {late} and was stopped") from None
        except asyncio.CancelledError:  # the caller went away: the worker is busy until its work ends
            give_back = False
            asyncio.ensure_future(self._drain(index, worker, wait, started, time_limit))
            raise
        except (EOFError, OSError):
            code = worker.process.exitcode
            self._replace(index, f"it ended (exit code {code})")
            raise ApiError(
                503,
                "solver_ended",
                f"the solver process ended during this request (exit code {code}); retry in {RETRY_AFTER} s",
            ) from None
        finally:
            if give_back:
                await self._give_back(index)
        return _unpacked(outcome)

    async def _within_limit(self, worker: _Worker, wait, started: float, time_limit: float | None):
        """The call's outcome; asyncio.TimeoutError (saying when it should have ended) once the
        worker is GRACE seconds past its call's deadline, or, before any of its loops started,
        past the limit and the build allowance."""
        if time_limit is None:
            return await asyncio.shield(wait)
        loop = asyncio.get_running_loop()
        building = started + time_limit + self.build_allowance + GRACE
        while True:
            deadline = worker.deadline.value
            late = deadline + GRACE if deadline > 0 else building
            done, _ = await asyncio.wait({wait}, timeout=max(min(late - loop.time(), POLL), 0.0))
            if done:
                return wait.result()
            if loop.time() >= late and worker.deadline.value == deadline:
                if deadline > 0:
                    raise TimeoutError(
                        f"within {GRACE:g} s past its deadline, {deadline - started:.3g} s "
                        f"after the call started (its time limit of {time_limit:g} s)"
                    )
                raise TimeoutError(
                    f"within {late - started:g} s (its time limit of {time_limit:g} s, "
                    f"{self.build_allowance:g} s of building and {GRACE:g} s of grace)"
                )

    async def _drain(self, index: int, worker: _Worker, wait, started: float, time_limit: float | None) -> None:
        """Wait out the work of a call nobody waits for any more, then free its worker."""
        try:
            await self._within_limit(worker, wait, started, time_limit)
        except TimeoutError:
            wait.add_done_callback(lambda f: f.exception())
            self._replace(index, "its work outlived its time limit after its caller went away")
        except (EOFError, OSError):
            self._replace(index, "it ended")
        finally:
            await self._give_back(index)

    def close(self) -> None:
        for worker in self._workers:
            if worker is not None:
                worker.end()
        self._readers.shutdown(wait=False, cancel_futures=True)


__all__ = ["GRACE", "SolverPool", "WORKER_NAME"]
