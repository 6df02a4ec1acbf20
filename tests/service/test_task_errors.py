"""One job's error never breaks another's (issue 54): every exception class of ours crosses a
process boundary whole, a worker returns a task's error as data, and on a live server each of
them fails its own job only, with its field and problem, while another key's simulation runs
on. The server imports this module as a plugin (its `raise_error` job kind)."""

from __future__ import annotations

import ast
import importlib
import os
import pickle
import time
from functools import lru_cache
from pathlib import Path

import pytest
from pydantic import Field

from flexmech.service.jobs.base import JSON, JobOptions, Plan, StoredJob, read_spec
from flexmech.service.jobs.kinds import register_job_kind
from flexmech.service.requests import Limits

REPO = Path(__file__).resolve().parents[2]
FIELD, PROBLEM = "/sections/flex/h", "must be positive, got -0.0001 m"


def _status():
    from flexmech.api.job_schemas import JobStatusResponse

    return JobStatusResponse(
        id="0" * 32,
        kind="sweep",
        status="running",
        progress={"done": 1, "total": 2, "failed_points": 0, "fraction": 0.5},
        timings={
            "created_at": "2026-01-01T00:00:00Z",
            "started_at": None,
            "finished_at": None,
            "elapsed_seconds": None,
        },
        links={"self": "/v1/jobs/x", "result": "/v1/jobs/x/result"},
    )


SAMPLES = {  # every exception class of ours: the arguments of one
    "MechanismError": lambda: (FIELD, PROBLEM, ((FIELD, PROBLEM), ("/loads/a/force/1", "not a number"))),
    "DuplicateKey": lambda: ("bodies",),
    "PluginError": lambda: ("FLEXMECH_PLUGINS names 'nowhere', which cannot be imported",),
    "IpoptOptionError": lambda: ("max_iter", "must be an integer"),
    "Gone": lambda: ("the kernel's graph was evicted",),
    "PenetratingStart": lambda: (2, 1.5e-6),
    "NoEnergyForm": lambda: ("spring 'k' is not the gradient of an energy",),
    "NoMassForm": lambda: ("link 'l' cannot express its kinetic energy",),
    "QuotaExceeded": lambda: ("bytes", 1200, 1000, 300),
    "ApiError": lambda: (404, "not_found", "no job 'x'", None),
    "FlexmechError": lambda: (429, "quota_exceeded", "full", None, {"quota": "jobs", "used": 5}),
    "JobTimeout": lambda: (_status(),),
    "OptionError": lambda: ("--samples", "must be positive"),
    "TaskFailed": lambda: ({"type": "MechanismError", "message": "/a: b", "pointer": "/a", "problem": "b"},),
    "_Unsafe": lambda: ("a call",),
    "RunStopped": lambda: ("stopped while evaluating states 32768 of 2000000",),
}


@lru_cache(maxsize=1)
def exception_classes() -> dict[str, type[BaseException]]:
    """Every exception class defined in flexmech's sources (found by their bases, transitively)."""
    trees = {}
    for folder in ("models", "service", "api", "flexmech"):
        for path in (REPO / folder).rglob("*.py"):
            module = "flexmech." + ".".join(path.relative_to(REPO).with_suffix("").parts)
            module = module.replace("flexmech.flexmech", "flexmech").removesuffix(".__init__")
            trees[module] = ast.parse(path.read_text())
    ours: dict[str, str] = {}
    grew = True
    while grew:
        grew = False
        for module, tree in trees.items():
            for node in ast.walk(tree):
                if not isinstance(node, ast.ClassDef) or node.name in ours:
                    continue
                bases = [b.id if isinstance(b, ast.Name) else getattr(b, "attr", "") for b in node.bases]
                if any(b.endswith(("Error", "Exception")) or b in ours for b in bases):
                    ours[node.name], grew = module, True
    found = {name: getattr(importlib.import_module(module), name) for name, module in ours.items()}
    return {name: cls for name, cls in found.items() if isinstance(cls, type) and issubclass(cls, BaseException)}


def make(name: str) -> BaseException:
    return exception_classes()[name](*SAMPLES[name]())


def test_every_exception_class_of_ours_pickles_to_an_equal_exception():
    classes = exception_classes()
    assert set(classes) == set(SAMPLES), "a new exception class needs a sample here (and must pickle)"
    for name, cls in classes.items():
        error = cls(*SAMPLES[name]())
        again = pickle.loads(pickle.dumps(error))
        assert type(again) is cls and str(again) == str(error), name
        assert {k: v for k, v in vars(again).items()} == {k: v for k, v in vars(error).items()}, name


# --- the plugin: a job kind whose task raises the exception its request names ------------------
class RaiseOptions(JobOptions):
    error: str = Field(max_length=64, description="the exception class raised in the worker")


class RaiseSpec(StoredJob, RaiseOptions):
    pass


class RaiseError:
    name, paged, Options = "raise_error", False, RaiseOptions
    route, operation_id, request_name = "raise-errors", "create_raise_error", "RaiseErrorRequest"
    title, summary, description, examples = "Raise", "A job whose task raises an exception of ours.", "Tests.", []

    def prepare(self, stored: JSON, limits: Limits) -> Plan:
        return Plan(1, {})

    def tasks(self, stored, plan, finished, chunk_size):
        return [] if finished else [{"indices": [0]}]

    def follow_up(self, stored, plan, task, finished, chunk_size):
        return []

    def run(self, stored: JSON, task: JSON) -> list[tuple[int, JSON]]:
        error = read_spec(RaiseSpec, stored).error
        if error == "exit":  # the worker dies under its task
            os._exit(3)
        raise make(error)

    def failed(self, point: JSON) -> bool:
        return False

    def result(self, stored, plan, finished) -> JSON:
        return {}


register_job_kind(RaiseError())
PLUGIN = "tests.service.test_task_errors"
KEYS = ("errors-first-key-0123", "errors-second-key-0123")
# key B's simulation: the rod of 8 elements over 1.5 s of 1 ms steps, stored per window
SIMULATION = {"example": "rod_free_vibration", "simulate": {"until": 1.5, "step": 0.001}}


def test_every_exception_raised_in_a_worker_fails_its_own_job_naming_its_field(request, tmp_path):
    import httpx
    from conftest import make_deployment  # here: the server imports this module, without the tests' path

    server = make_deployment("sqlite", request, tmp_path).start(FLEXMECH_PLUGINS=PLUGIN)
    try:
        errors = {}
        for name in SAMPLES:
            job = httpx.post(server.url + "/v1/raise-errors", json={"example": "gripper", "error": name}).json()
            errors[name] = _final(server.url, job["id"])
        log = server.output(tail=None)
    finally:
        server.stop()
    for name, status in errors.items():
        expected = make(name)
        assert status["status"] == "failed" and status["error"] == f"a task failed: {name}: {expected}", name
    assert f"a task failed: MechanismError: {FIELD}: {PROBLEM}" == errors["MechanismError"]["error"]
    assert "process pool broke" not in log


def _final(url: str, job_id: str, timeout: float = 120) -> dict:
    import httpx

    deadline = time.monotonic() + timeout
    while (status := httpx.get(f"{url}/v1/jobs/{job_id}").json())["status"] in ("queued", "running"):
        assert time.monotonic() < deadline
        time.sleep(0.05)
    return status


@pytest.mark.parametrize("backend", ["sqlite", "postgresql"])
def test_exports_refused_while_they_run_leave_another_keys_simulation_whole(backend, request, tmp_path):
    """Issue 54's reproduction: key A's exports fail in the worker (one Newton step without a
    line search cannot converge along the example path) while key B's simulation runs."""
    from conftest import make_deployment

    from flexmech.api.client import Client

    server = make_deployment(backend, request, tmp_path).start(FLEXMECH_API_KEYS=",".join(KEYS))
    try:
        with Client(server.url, api_key=KEYS[0]) as first, Client(server.url, api_key=KEYS[1]) as second:
            simulation = second.simulation(**SIMULATION)
            exports = [first.export(example="gripper", max_iterations=1, line_search_halvings=0) for _ in range(3)]
            failed = [first.wait(job.id, timeout=300) for job in exports]
            whole = second.wait(simulation.id, timeout=600)
        log = server.output(tail=None)
    finally:
        server.stop()
    assert all(job.status == "failed" and "a task failed: MechanismError: " in job.error for job in failed), failed
    assert whole.status == "succeeded" and whole.progress.done == whole.progress.total, whole
    assert "process pool broke" not in log and "BrokenProcessPool" not in log


def test_a_worker_that_dies_under_its_task_fails_that_job_only(request, tmp_path):
    """A task that kills its worker each time it runs: its job fails after its second try, and
    another key's sweep, whose tasks the broken pool took down with it twice, runs again
    uncharged and succeeds with every point once."""
    from conftest import make_deployment

    from flexmech.api.client import Client

    server = make_deployment("sqlite", request, tmp_path).start(
        FLEXMECH_PLUGINS=PLUGIN, FLEXMECH_API_KEYS=",".join(KEYS), FLEXMECH_CHUNK_SIZE="16"
    )
    sweep = {"path": "/loads/actuation/force/1", "start": -60, "stop": 60, "steps": 799}
    try:
        with Client(server.url, api_key=KEYS[0]) as first, Client(server.url, api_key=KEYS[1]) as second:
            steady = second.sweep(example="gripper_exact", outputs=["end_effector.x"], parameters=[sweep])
            while second.job(steady.id).progress.done < 32:
                time.sleep(0.05)
            dying = first.jobs.raise_error(example="gripper", error="exit")
            died = first.wait(dying.id, timeout=300)
            whole = second.wait(steady.id, timeout=600)
            indices = [p.index for p in second.result(steady.id).result.points]
        log = server.output(tail=None)
    finally:
        server.stop()
    assert died.status == "failed" and "BrokenProcessPool" in died.error, died
    assert whole.status == "succeeded" and indices == list(range(800)), whole.error
    assert log.count(f"job {died.id}: the worker running its task died") == 2
    assert log.count("the worker running its task died") == 2  # the sweep's tasks were never charged
