"""Kernels are compiled by the build queue, never inside a request: a build over its time or
memory limit is abandoned with a note and not tried again; a request only asks for a build
and runs interpreted; a server stopped or killed (SIGKILL) leaves no builder, compiler or
worker behind (its process groups are listed)."""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path

import httpx
import numpy as np
import pytest
from conftest import EXAMPLES
from servers import ApiServer

from flexmech.models import compile_mechanism, load_document
from flexmech.models.kernels.chain_signature import ChainSignature
from flexmech.models.kernels.chunks import chunks
from flexmech.service.kernels.build import BuildLimits, Compiler
from flexmech.service.kernels.cache import abandoned, compiled_for, is_compiled
from flexmech.service.kernels.queue import Builder, accept_requests, build_chain, queue_dir, request_chain

SMALL = ChainSignature(1, False, False)  # the cheapest kernels there are: a second or two of gcc


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("FLEXMECH_CACHE_DIR", str(tmp_path / "cache"))
    yield tmp_path / "cache"
    accept_requests(False)


def test_a_compile_over_its_time_limit_is_killed_and_noted(cache):
    outcome = build_chain(ChainSignature(3, True, True), Compiler(), BuildLimits(seconds=0.3))
    assert not outcome.ok and "exceeded its time limit of 0.3 s" in outcome.message
    note = json.loads(abandoned(ChainSignature(3, True, True)).read_text())
    assert "time limit" in note["message"]
    assert not is_compiled(ChainSignature(3, True, True))


@pytest.mark.parametrize("mib", [25, 40, 120])
def test_a_compile_over_its_memory_limit_fails_and_is_noted(cache, mib):
    """gcc 12 on this machine ends in a different way at each limit: cc1 crashes (25 MiB), the
    loader cannot map cc1's libraries (40), an allocation is refused with a message (120); each
    is the memory limit, and says so (the crash was once reported as a compiler failure)."""
    outcome = Compiler().build(
        chunks(ChainSignature(3, True, True)).factor, cache / "factor.so", BuildLimits(memory_bytes=mib * 2**20)
    )
    assert not outcome.ok and f"memory limit of {mib} MiB" in outcome.message, outcome.message
    assert not (cache / "factor.so").exists()


def test_an_abandoned_key_is_not_asked_for_again(cache):
    build_chain(SMALL, Compiler(), BuildLimits(seconds=0.01))
    accept_requests(True)
    assert abandoned(SMALL).exists() and not request_chain(SMALL)
    assert not list(queue_dir().glob("*.json")) if queue_dir().exists() else True


def test_compiled_kernels_compute_what_the_interpreted_ones_do(cache):
    outcome = build_chain(SMALL, Compiler(), BuildLimits())
    assert outcome.ok, outcome.message
    compiled = compiled_for([SMALL])[SMALL]
    interpreted = chunks(SMALL)
    rng = np.random.default_rng(3)
    for kind in ("sweep", "jacobian", "factor", "backward", "substitute"):
        fn, native = interpreted.functions()[kind], compiled.functions()[kind]
        args = [rng.standard_normal(fn.sparsity_in(i).shape) for i in range(fn.n_in())]
        args[0] = np.ones(fn.sparsity_in(0).shape)  # every item runs
        for a, b in zip(fn(*args), native(*args)):
            np.testing.assert_allclose(np.asarray(b), np.asarray(a), rtol=1e-12, atol=1e-12)


def test_a_run_asks_for_its_kernels_and_goes_on_interpreted(cache):
    """The rod's run in a process that takes build requests: a request file, no library."""
    from flexmech.service.dynamics.run import run_simulation, simulation_spec

    accept_requests(True)
    mech = compile_mechanism(load_document(EXAMPLES / "rod_free_vibration.json"))
    _, report = run_simulation(mech, simulation_spec(mech, {"until": 0.01}))
    assert report["status"] == "finished"
    requests = [json.loads(p.read_text()) for p in queue_dir().glob("*.json")]
    assert [r["signature"] for r in requests] == [{"degree": 3, "shear": True, "axial": True, "rule": "interpolated"}]
    assert not list((cache / "kernels").rglob("*.so"))
    # what the server's builder does with a request (a cheap one: the rod's takes 20 s of gcc)
    for request in queue_dir().glob("*.json"):
        request.unlink()
    assert request_chain(SMALL)
    Builder(BuildLimits()).run_one(next(queue_dir().glob("*.json")))
    assert is_compiled(SMALL) and not list(queue_dir().glob("*.json"))


# ---- a real server: its builder and compilers end with it -------------------------------------
def _descendants(root: int) -> dict[int, str]:
    """pid -> command name of every process under `root` (from /proc)."""
    parents: dict[int, list[int]] = {}
    names: dict[int, str] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        name = stat[stat.index("(") + 1 : stat.rindex(")")]
        ppid = int(stat[stat.rindex(")") + 2 :].split()[1])
        parents.setdefault(ppid, []).append(int(entry.name))
        names[int(entry.name)] = name
    out, todo = {}, [root]
    while todo:
        for child in parents.get(todo.pop(), []):
            out[child] = names[child]
            todo.append(child)
    return out


def _alive(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rindex(")") + 2] != "Z"


def _server_compiling(tmp_path: Path) -> tuple[ApiServer, dict[int, str]]:
    """A server on an empty cache, its builder compiling the four-bar's kernels (asked for by
    a simulation with the old `compiled: true`), a simulation job running on a worker."""
    env = {
        "FLEXMECH_DATA_DIR": str(tmp_path / "data"),
        "FLEXMECH_WORKERS": "1",
        "FLEXMECH_API_KEYS": "",
        "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
        "FLEXMECH_CACHE_DIR": str(tmp_path / "cache"),
    }
    server = ApiServer(env, tmp_path / "server.log")
    job = httpx.post(
        f"{server.url}/v1/simulations",
        json={"example": "four_bar_dynamics", "simulate": {"until": 1.0, "compiled": True}},
        timeout=30,
    )
    assert job.status_code == 202, job.text
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        family = _descendants(server.proc.pid)
        if any(name in ("cc1", "gcc", "cc") for name in family.values()):
            return server, family
        time.sleep(0.05)
    server.kill()
    raise AssertionError("no compiler started:\n" + server.output())


@pytest.mark.parametrize("how", ["SIGTERM", "SIGKILL"])
def test_a_stopped_or_killed_server_leaves_no_builder_compiler_or_worker(tmp_path, how):
    server, family = _server_compiling(tmp_path)
    builder = httpx.get(f"{server.url}/v1/health").json()["builder"]
    assert builder["running"] and builder["pid"] in family
    os.kill(server.proc.pid, getattr(signal, how))  # the server alone: as an orchestrator, or a crash
    server.proc.wait(30)
    deadline = time.monotonic() + 15
    while time.monotonic() < deadline and any(_alive(pid) for pid in family):
        time.sleep(0.1)
    survivors = {pid: name for pid, name in family.items() if _alive(pid)}
    for pid in survivors:
        os.kill(pid, signal.SIGKILL)
    server.stop()
    assert not survivors, f"outlived the server ({how}): {survivors}"
