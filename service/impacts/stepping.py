"""Chunks of steps of an impact model in one CasADi call: `event_step` or `moreau_step`
chained by mapaccum, run compiled when the kernel cache has the chunk's library (built by the
build queue, service.kernels.queue, or `flexmech build`; keyed by the model's structure) and
on CasADi's virtual machine until then, and the Python loops that run them to the end time."""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from functools import lru_cache

import casadi as ca
import numpy as np

from flexmech.models.elements import FAMILIES
from flexmech.models.impacts.model import WORKS, ImpactModel
from flexmech.service.impacts.event_driven import EventLayout, event_step
from flexmech.service.impacts.kept_rows import KeptRows
from flexmech.service.impacts.moreau import moreau_step
from flexmech.service.impacts.native import NativeFunction
from flexmech.service.impacts.state_sensitivity import SensitivityChunk
from flexmech.service.kernels.queue import function_library, request_function

EVENT_CHUNK = 2000  # trial steps per call
MOREAU_CHUNK = 5000
MAX_CACHED = 32  # chunk Functions kept in memory
KEPT_EVENT_ROWS = 100_000  # states an event-driven run holds (service.impacts.kept_rows)
STEP_SOURCES = ("stepping", "moreau", "event_driven", "contact_forces")  # of service.impacts: the chunks' graphs


@lru_cache(maxsize=4)
def _code_version(family_sources: tuple[str, ...]) -> str:
    """A digest of the sources the step graphs come from (the impact model, the contact laws,
    the element families, the statics context their energies are written in, the steps): a
    cached library built from older code is never loaded."""
    import hashlib
    from pathlib import Path

    import flexmech.models.contact.laws as laws
    import flexmech.models.elements as families
    import flexmech.models.graph.context as statics_context  # the statics energies of models.impacts.families read it
    import flexmech.models.graph.loads as statics_loads  # the bodies' kinetic energy, gravity and loads (models.impacts.coordinates)
    import flexmech.models.impacts as built

    here = Path(__file__).parent
    folders = [Path(module.__file__).parent for module in (built, laws, families)]
    sources = (
        [path for folder in folders for path in sorted(folder.glob("*.py"))]
        + [here / f"{name}.py" for name in STEP_SOURCES]
        + [Path(statics_context.__file__), Path(statics_loads.__file__)]
        + [Path(source) for source in family_sources]
    )  # a family registered from elsewhere too
    digest = hashlib.sha256()
    for source in sources:
        digest.update(source.read_bytes())
    return digest.hexdigest()[:16]


@dataclass
class Trace:
    """Accepted states, rows of the state vector (event-driven: EventLayout; moreau: [t, q, v,
    works]), and moreau's impulses and active flags per step."""

    states: list[np.ndarray] = field(default_factory=list)
    extras: list[np.ndarray] = field(default_factory=list)
    status: str = "finished"
    message: str = ""
    calls: int = 0
    seconds: float = 0.0
    steps: int | None = None  # accepted steps, when `states` holds only some of them
    derivatives: np.ndarray | None = None  # event-driven: d (end state) / d numbers (state_sensitivity)


class Chunk:
    """Chunks of steps with fixed parameters: run(S) -> outputs as arrays of shape
    (steps, rows). Compiled (through ctypes, no copies) or on CasADi's virtual machine."""

    def __init__(self, fn: ca.Function, library, columns: list[np.ndarray]):
        shapes_in = [(fn.size1_in(k), fn.size2_in(k)) for k in range(fn.n_in())]
        shapes_out = [(fn.size1_out(k), fn.size2_out(k)) for k in range(fn.n_out())]
        self.native = NativeFunction(library, fn.name(), shapes_in, shapes_out) if library is not None else None
        self.fn = fn
        self.fixed = [] if library is not None else [tiled(c, shapes_in[k + 1][1]) for k, c in enumerate(columns)]
        if self.native is not None:
            for k, c in enumerate(columns):
                self.native.inputs[k + 1][:] = np.asarray(c, dtype=float).ravel()

    def run(self, S: np.ndarray) -> list[np.ndarray]:
        if self.native is not None:
            self.native.inputs[0][0] = S
            self.native()
            return [out.copy() for out in self.native.outputs]
        return [np.asarray(out).T for out in self.fn.call([ca.DM(S), *self.fixed])]


_FUNCTIONS: dict[tuple, tuple] = {}


def chunk_function(model: ImpactModel, kind: str) -> tuple[ca.Function, str]:
    """The chunk Function of a model's structure and its key in the kernel cache."""
    if kind == "event":
        fn = event_step(model).mapaccum("event_chunk", EVENT_CHUNK)
    else:
        fn = moreau_step(model).mapaccum("moreau_chunk", MOREAU_CHUNK, ["S"], ["S1"])
    return fn, f"{_code_version(FAMILIES.sources())}|{kind}|{model.structure_key()}"


def chunk(model: ImpactModel, kind: str, columns: list[np.ndarray]) -> Chunk:
    """The chunk of a model's structure with these fixed inputs (parameters, settings):
    compiled when the cache has its library; else interpreted, and the build queue asked."""
    key = (kind, model.structure_key(), threading.get_ident())
    fn, cache_key = _FUNCTIONS.get(key, (None, None))
    if fn is None:
        fn, cache_key = chunk_function(model, kind)
        if len(_FUNCTIONS) >= MAX_CACHED:  # the oldest goes (a study or a service sees many)
            _FUNCTIONS.pop(next(iter(_FUNCTIONS)))
        _FUNCTIONS[key] = (fn, cache_key)
    target = function_library(fn, cache_key)
    if not target.exists():
        request_function(fn, cache_key)
        target = None
    return Chunk(fn, target, columns)


def tiled(column: np.ndarray, count: int) -> ca.DM:
    """A mapaccum's per-step input, repeated once per run: passing one column makes CasADi
    repeat it at every call, which costs several times the steps themselves."""
    return ca.DM(np.tile(np.asarray(column, dtype=float).reshape(-1, 1), (1, count)))


def event_settings(model: ImpactModel, until: float, tolerance: float, max_step: float) -> np.ndarray:
    """[until, rtol, h_max, atol per q and v]: lengths to `tolerance` of the smallest pair scale,
    angles to that over the largest lever, velocities per millisecond of those."""
    length = min(pair.length_scale for pair in model.pairs)
    atol_q = []
    for name in model.coordinate_names():
        atol_q.append(tolerance * (length if not name.endswith(".theta") else length / max(1.0, 10 * length)))
    atol = np.array(atol_q + [a * 1e3 for a in atol_q])
    return np.concatenate([[until, tolerance, max_step], atol])


def run_events(
    model: ImpactModel,
    p: np.ndarray,
    q0,
    v0,
    until: float,
    tolerance: float,
    first_step: float,
    max_step: float,
    max_calls: int,
    stop=None,
    progress=None,
    directions: np.ndarray | None = None,
) -> Trace:
    """`directions`: d p / d number, one column per number the end state is differentiated by."""
    n, P = model.bodies.size, len(model.pairs)
    L = EventLayout(n, P)
    S = np.zeros(L.size)
    S[L.y] = np.concatenate([q0, v0, np.zeros(len(WORKS))])
    S[L.at("h")] = first_step
    settings = event_settings(model, until, tolerance, max_step)
    if directions is None:
        steps = chunk(model, "event", [p, settings])
    else:
        steps = SensitivityChunk(model, p, directions, settings, EVENT_CHUNK)
    trace = Trace()
    rows = KeptRows(KEPT_EVENT_ROWS, L.at("event"))
    rows.add(S.reshape(1, -1).copy())
    reached = float(S[0])
    began = time.perf_counter()
    while S[0] < until * (1 - 1e-15):
        out = steps.run(S)[0]
        trace.calls += EVENT_CHUNK
        accepted = out[out[:, L.at("accepted")] > 0.5]
        if len(accepted):
            rows.add(accepted)
            reached = float(accepted[-1, 0])
        S = out[-1]
        if _ended(trace, S, stop, progress, reached):
            break
        if trace.calls >= max_calls:
            trace.status, trace.message = "step_limit", f"{max_calls} trial steps reached at t = {S[0]:g} s"
            break
    trace.seconds = time.perf_counter() - began
    trace.states, trace.steps = [rows.rows()], rows.seen - 1
    if directions is not None:
        trace.derivatives = steps.derivatives
    if rows.stride > 1:
        trace.message = (trace.message + "; " if trace.message else "") + (
            f"held {len(rows)} of {rows.seen - 1} steps (every contact event among them)"
        )
    return trace


def _ended(trace: Trace, S: np.ndarray, stop, progress, reached: float) -> bool:
    """After a chunk: report progress; end the run (saying why) on a state that is no longer
    finite, or when asked to stop."""
    if progress is not None:
        progress(float(S[0]))
    if not np.all(np.isfinite(S)):
        trace.status, trace.message = "not_converged", f"the state stopped being finite near t = {reached:g} s"
        return True
    if stop is not None and stop():
        trace.status, trace.message = "stopped", f"stopped at t = {S[0]:g} s"
        return True
    return False


def run_moreau(model: ImpactModel, p: np.ndarray, q0, v0, until: float, h: float, stop=None, progress=None) -> Trace:
    S = np.concatenate([[0.0], q0, v0, np.zeros(len(WORKS))])
    count = round(until / h)
    steps = chunk(model, "moreau", [p, np.array([h])])
    trace = Trace()
    trace.states.append(S.reshape(1, -1).copy())
    trace.extras.append(np.zeros((1, 5 * len(model.pairs) + model.constraints.numel())))
    done = 0
    began = time.perf_counter()
    while done < count:
        states, impulses, active, pins = steps.run(S)
        take = min(MOREAU_CHUNK, count - done)
        trace.states.append(states[:take])
        trace.extras.append(np.hstack([impulses, active, pins])[:take])
        S = states[take - 1]
        done += take
        trace.calls += take
        if _ended(trace, S, stop, progress, float(S[0])):
            break
    trace.seconds = time.perf_counter() - began
    return trace
